"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0.

The surface (implicit.py) is built from shapes, volumes or meshes (mesh_sdf.py, winding.py);
its band and the band form of data are in band.py, the device state of a flow's data on the
band lists or bricks in storage.py. The flows: flows.py (heat, TV, TV denoising, diffusion
along a field; TV's dynamic lambda in dynamic_lambda.py), harmonic.py (harmonic maps and
colour), textures.py (Turk's reaction-diffusion), curvature.py (principal directions),
inpainting.py (filling missing data);
level_set.py reinitialises psi and extends data by PDE, sampling.py reads data at points,
render.py draws and exports, shapes.py makes sample shapes and their data, runs.py holds
the command line's ready-made runs.
"""

from ..grid3d import Grid3D
from .band import INTERPOLATIONS
from .curvature import principal_directions
from .flows import SurfaceDenoiseInfo, denoise_tv, diffuse_along, heat, stability_limit, tv
from .harmonic import denoise_colour, harmonic_map
from .implicit import ImplicitSurface
from .inpainting import SurfaceInpaintInfo, inpaint
from .render import colormap, export_mesh, render, render_mesh, to_mesh
from .shapes import SURFACE_SHAPES, checker, colour_pattern, surface_noise, surface_shape
from .textures import THESIS_FIG_4_7, TURK, reaction_diffusion

__all__ = [
    "INTERPOLATIONS",
    "SURFACE_SHAPES",
    "THESIS_FIG_4_7",
    "TURK",
    "Grid3D",
    "ImplicitSurface",
    "checker",
    "colormap",
    "colour_pattern",
    "SurfaceDenoiseInfo",
    "SurfaceInpaintInfo",
    "denoise_colour",
    "denoise_tv",
    "diffuse_along",
    "export_mesh",
    "harmonic_map",
    "heat",
    "inpaint",
    "principal_directions",
    "reaction_diffusion",
    "render",
    "render_mesh",
    "stability_limit",
    "surface_noise",
    "surface_shape",
    "to_mesh",
    "tv",
]
