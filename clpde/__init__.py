"""clpde: PDE-based image processing (inpainting, diffusion, level sets) as OpenCL kernels."""

# First: importing it turns Ctrl-C into one line while the libraries below load.
from . import _interrupt  # noqa: F401  # isort: skip

from ._version import __version__  # noqa: F401  (clpde.__version__)
from .errors import ClpdeError, InputError, KernelBuildError, NoDeviceError

# Each public name and the module that holds it, imported on first use (as scikit-image's
# lazy loader does): `import clpde` then costs the errors module, not scipy.signal (film),
# trimesh (surfaces) and the rest, which every command would otherwise pay before it starts.
_LAZY = {
    "detect_defects": "film",
    "inpaint_video": "film",
    "grow_mask": "imagedata",
    "Inpainting": "inpainting.api",
    "inpaint": "inpainting.api",
    "FLOWS": "planar.flows",
    "PlanarFlow": "planar.flows",
    "diffuse": "planar.flows",
    "stability_limit": "planar.flows",
    "denoise_tv": "planar.rof",
    "track_region": "regions.api",  # region tracking on deforming surfaces (section 2.2)
    "devices": "runtime",
    "get_runtime": "runtime",
    "use_device": "runtime",
    "batch": "scale.batch",  # many files over Dask workers (needs clpde[batch])
    "MorphingTracker": "tracking.tracker",
    "track": "tracking.tracker",
}

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
# `clpde.inpainting.available()`, `clpde.data.damaged_astronaut()`,
# `clpde.surface.ImplicitSurface`); the others stay importable (`import clpde.planar.rof`)
# but are left out of dir(clpde), so that it lists what a user calls, as scikit-image's does.
PUBLIC_MODULES = ("data", "inpainting", "io", "surface")


def __getattr__(name: str):
    import importlib

    if name in _LAZY:
        value = getattr(importlib.import_module(f"{__name__}.{_LAZY[name]}"), name)
        globals()[name] = value  # later lookups skip this function
        return value
    if name in PUBLIC_MODULES:  # as `import clpde.inpainting` would
        return importlib.import_module(f"{__name__}.{name}")
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def __dir__() -> list[str]:
    return sorted({*__all__, *PUBLIC_MODULES, "__version__"})
