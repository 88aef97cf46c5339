"""clpde: PDE-based image processing (inpainting, diffusion, level sets) as OpenCL kernels."""

from . import (
    data,  # test images and scenes, like skimage.data
    surface,  # clpde.surface.ImplicitSurface and the chapter-4 flows
)
from ._version import __version__  # noqa: F401  (clpde.__version__)
from .errors import ClpdeError, InputError, KernelBuildError, NoDeviceError
from .inpainting.api import Inpainting, inpaint
from .planar.flows import FLOWS, PlanarFlow, diffuse, stability_limit
from .planar.rof import denoise_tv
from .regions.tracker import track_region  # region tracking on deforming surfaces (section 2.2)
from .runtime import devices, get_runtime, use_device
from .scale.batch import batch  # many files over Dask workers (needs clpde[batch]; imported lazily)
from .tracking.contours import MorphingTracker, track

__all__ = [
    "FLOWS",
    "ClpdeError",
    "Inpainting",
    "InputError",
    "KernelBuildError",
    "MorphingTracker",
    "NoDeviceError",
    "PlanarFlow",
    "batch",
    "data",
    "denoise_tv",
    "devices",
    "diffuse",
    "get_runtime",
    "inpaint",
    "stability_limit",
    "surface",
    "track",
    "track_region",
    "use_device",
]
