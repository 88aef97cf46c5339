"""clpde: PDE-based image processing (inpainting, diffusion, level sets) as OpenCL kernels."""

# First: importing it turns Ctrl-C into one line while the libraries below load.
from . import _interrupt  # noqa: F401  # isort: skip

from . import (
    data,  # test images and scenes, like skimage.data
    surface,  # clpde.surface.ImplicitSurface and the chapter-4 flows
)
from ._version import __version__  # noqa: F401  (clpde.__version__)
from .errors import ClpdeError, InputError, KernelBuildError, NoDeviceError
from .film import detect_defects, inpaint_video
from .imagedata import grow_mask
from .inpainting.api import Inpainting, inpaint
from .planar.flows import FLOWS, PlanarFlow, diffuse, stability_limit
from .planar.rof import denoise_tv
from .regions.api import track_region  # region tracking on deforming surfaces (section 2.2)
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
    "detect_defects",
    "devices",
    "diffuse",
    "get_runtime",
    "grow_mask",
    "inpaint",
    "inpaint_video",
    "stability_limit",
    "surface",
    "track",
    "track_region",
    "use_device",
]

# The submodules that are public API besides the names above (`clpde.io.read_image`,
# `clpde.inpainting.available()`); the others stay importable (`import clpde.rof`) but are
# left out of dir(clpde), so that it lists what a user calls, as scikit-image's does.
PUBLIC_MODULES = ("data", "inpainting", "io", "surface")


def __getattr__(name: str):
    if name in PUBLIC_MODULES:  # loaded on first use, as `import clpde.inpainting` would
        import importlib

        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*__all__, *PUBLIC_MODULES, "__version__"})
