"""PDEs on implicit surfaces (thesis chapter 4): data on a narrow band around psi = 0.

The public face is `ImplicitSurface`: the flows are its methods and nowhere else public
(``surf.heat(u, t)``, ``surf.denoise_colour(rgb, t)``, ``surf.render(u, "out.png")``, ...).
Next to it: `inpaint` (on a surface or a mesh), the mesh tools that take a mesh
(`render_mesh`, `export_mesh`, `colormap`), and the sample shapes and data.

The surface (implicit.py) is built from shapes, volumes or meshes (mesh_sdf.py, winding.py);
its band and the band form of data are in band.py, the device state of a flow's data on the
band lists or bricks in storage.py. Its methods (flow_methods.py, shape_methods.py) call the
implementations: flows.py (heat, TV, TV denoising, diffusion along a field; TV's dynamic
lambda in dynamic_lambda.py), harmonic.py (harmonic maps and colour), textures.py (Turk's
reaction-diffusion), curvature.py (principal directions), render.py (meshes, pictures,
export). inpainting.py fills missing data, level_set.py reinitialises psi and extends data
by PDE, sampling.py reads data at points, shapes.py makes sample shapes and their data,
runs.py holds the command line's ready-made runs.
"""

from ..grid3d import Grid3D
from .band import INTERPOLATIONS
from .flows import SurfaceDenoiseInfo
from .implicit import ImplicitSurface
from .inpainting import SurfaceInpaintInfo, inpaint
from .render import colormap, export_mesh, render_mesh
from .shapes import SURFACE_SHAPES, checker, colour_pattern, surface_noise, surface_shape
from .textures import THESIS_FIG_4_7, TURK

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
    "export_mesh",
    "inpaint",
    "render_mesh",
    "surface_noise",
    "surface_shape",
]
