"""Method comparisons at equal budget against a reference (`restir compare`, `restir.compare`)."""
from .metrics import flip, mape, relmse
from .runner import Comparison, MethodResult, MethodSpec, compare

__all__ = ["compare", "Comparison", "MethodResult", "MethodSpec", "relmse", "mape", "flip"]
