"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0."""

from .flows import heat, stability_limit
from .grid3d import Grid3D
from .implicit import INTERPOLATIONS, ImplicitSurface

__all__ = ["INTERPOLATIONS", "Grid3D", "ImplicitSurface", "heat", "stability_limit"]
