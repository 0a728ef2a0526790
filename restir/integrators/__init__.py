"""Integrators (methods). Each is a pipeline of stages; `METHODS` maps CLI names to classes."""
from .path import PathTracer
from .restir_di.pipeline import ReSTIRDI
from .restir_pt.pipeline import ReSTIRPT
from .suffix_restir.pipeline import SuffixReSTIR

METHODS = {"pt": PathTracer, "restir-di": ReSTIRDI, "restir-pt": ReSTIRPT, "suffix-restir": SuffixReSTIR}
