"""restir: a research renderer for resampled path tracing on NVIDIA Warp.

Public API: `load_scene`, `render`, `view`, `write_image`, `RenderConfig`, `RenderResult`, and for
animated scenes `animate`, `Motion`, `Keyframes`.
"""
import os as _os
import re as _re

import warp as _wp

# Warp prints a banner, one line per compiled module and a CUDA-driver warning on CPU-only
# machines; keep the CLI's output to our own (RESTIR_WARP_VERBOSE=1 restores Warp's; 0 means off).
if _os.environ.get("RESTIR_WARP_VERBOSE", "").strip().lower() not in ("1", "true", "yes", "on"):
    _wp.config.log_level = _wp.LOG_ERROR
# No kernel is differentiated: skip adjoint code generation (halves compile times).
_wp.config.enable_backward = False
# Kernels run faster when the CPU compiler inlines more: Warp passes structs by value, so a
# function left out of line copies its struct arguments (SceneDevice is about 1 KB) at every
# call. LLVM's inlining threshold raised from Warp's 9000 to 40000 made the path tracer's frame
# 4-5% shorter and left the images bit-identical; compiling pt's kernels takes 25 s instead of
# 17 (docs/changelog.md#speed-llvms-inline-threshold-40000).
_flags = _wp.config.cpu_compiler_flags
if _flags is not None and "inline-threshold=" in _flags:
    _wp.config.cpu_compiler_flags = _re.sub(r"inline-threshold=\d+", "inline-threshold=40000", _flags)

from .api import RenderResult, load_scene, render, write_image
from .config import ConfigError, RenderConfig
from .scene.animation import Keyframes, Motion, animate
from .scene.errors import SceneError, SceneWarning
from .viewer import view

__all__ = ["load_scene", "render", "view", "write_image", "RenderConfig", "RenderResult", "SceneError", "SceneWarning",
           "ConfigError", "animate", "Motion", "Keyframes"]
__version__ = "0.1.0"
