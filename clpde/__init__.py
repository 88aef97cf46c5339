"""clpde: PDE-based image processing (inpainting, diffusion, level sets) as OpenCL kernels."""

from . import (
    data,  # test images and scenes, like skimage.data
    surface,  # clpde.surface.ImplicitSurface and the chapter-4 flows
)
from .batch import batch  # many files over Dask workers (needs clpde[batch]; imported lazily)
from .film import detect_defects, inpaint_video
from .imagedata import InputError
from .inpaint import Inpainting, inpaint
from .planar import FLOWS, PlanarFlow, diffuse, stability_limit
from .regions import track_region  # region tracking on deforming surfaces (section 2.2)
from .rof import denoise_tv
from .runtime import ClpdeError, KernelBuildError, NoDeviceError, devices, get_runtime, use_device
from .track import MorphingTracker, track

__version__ = "0.1.0"

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
    "detect_defects",
    "devices",
    "diffuse",
    "get_runtime",
    "inpaint",
    "inpaint_video",
    "stability_limit",
    "surface",
    "track",
    "track_region",
    "use_device",
]
