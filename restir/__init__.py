"""restir: a research renderer for resampled path tracing on NVIDIA Warp.

Public API: `load_scene`, `render`, `write_image`, `RenderConfig`, `RenderResult`.
"""
import os as _os

import warp as _wp

# Warp prints a banner, one line per compiled module and a CUDA-driver warning on CPU-only
# machines; keep the CLI's output to our own (RESTIR_WARP_VERBOSE=1 restores Warp's; 0 means off).
if _os.environ.get("RESTIR_WARP_VERBOSE", "").strip().lower() not in ("1", "true", "yes", "on"):
    _wp.config.log_level = _wp.LOG_ERROR
# No kernel is differentiated: skip adjoint code generation (halves compile times).
_wp.config.enable_backward = False

from .api import RenderResult, load_scene, render, write_image
from .config import ConfigError, RenderConfig
from .scene.errors import SceneError, SceneWarning

__all__ = ["load_scene", "render", "write_image", "RenderConfig", "RenderResult", "SceneError", "SceneWarning",
           "ConfigError"]
__version__ = "0.1.0"
