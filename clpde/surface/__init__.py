"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0."""

from ..grid3d import Grid3D
from .flows import (
    THESIS_FIG_4_7,
    TURK,
    SurfaceDenoiseInfo,
    denoise_colour,
    denoise_tv,
    diffuse_along,
    harmonic_map,
    heat,
    principal_directions,
    reaction_diffusion,
    stability_limit,
    tv,
)
from .implicit import INTERPOLATIONS, ImplicitSurface
from .render import colormap, export_mesh, render, render_mesh, to_mesh

__all__ = [
    "INTERPOLATIONS",
    "THESIS_FIG_4_7",
    "TURK",
    "Grid3D",
    "ImplicitSurface",
    "colormap",
    "SurfaceDenoiseInfo",
    "denoise_colour",
    "denoise_tv",
    "diffuse_along",
    "export_mesh",
    "harmonic_map",
    "heat",
    "principal_directions",
    "reaction_diffusion",
    "render",
    "render_mesh",
    "stability_limit",
    "to_mesh",
    "tv",
]
