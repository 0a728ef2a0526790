"""The GPU check and the bundle that brings it to a bare device machine (docs/guide/gpu.md)."""
