"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0."""

from .flows import denoise_tv, diffuse_along, harmonic_map, heat, stability_limit, tv
from .grid3d import Grid3D
from .implicit import INTERPOLATIONS, ImplicitSurface

__all__ = [
    "INTERPOLATIONS", "Grid3D", "ImplicitSurface", "denoise_tv", "diffuse_along",
    "harmonic_map", "heat", "stability_limit", "tv",
]
