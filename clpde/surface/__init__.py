"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0."""

from ..grid3d import Grid3D
from .band import INTERPOLATIONS
from .curvature import principal_directions
from .flows import SurfaceDenoiseInfo, denoise_tv, diffuse_along, heat, stability_limit, tv
from .harmonic import denoise_colour, harmonic_map
from .implicit import ImplicitSurface
from .render import colormap, export_mesh, render, render_mesh, to_mesh
from .textures import THESIS_FIG_4_7, TURK, reaction_diffusion

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
