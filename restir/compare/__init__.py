"""Method comparisons at equal budget against a reference (`restir compare`, `restir.compare`)."""
from .metrics import flip, mape, relmse
from .config import CompareConfig
from .runner import Comparison, MethodResult, MethodSpec, compare

__all__ = ["compare", "CompareConfig", "Comparison", "MethodResult", "MethodSpec", "relmse", "mape", "flip"]
