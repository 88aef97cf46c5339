"""Inpainting: `clpde.inpaint` and `clpde.Inpainting` (api.py), the method registry
(registry.py) and one module per method."""

from .registry import METHODS, available, load

__all__ = ["METHODS", "available", "load"]
