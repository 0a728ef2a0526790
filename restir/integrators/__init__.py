"""Integrators (methods). Each is a pipeline of stages; `METHODS` maps CLI names to classes."""
from .path import PathTracer

METHODS = {"pt": PathTracer}
