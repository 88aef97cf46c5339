"""Inpainting: `inpaint` and `Inpainting` (api.py; also `clpde.inpaint`), the method registry
(registry.py) and one module per method, each with its frozen options class (imported on
first use: ``from clpde.inpainting import SpectralOptions``)."""

import importlib

from .registry import METHODS, Method, available, load, options, register

# the entry points and each method's options class -> its module (imported when the name is
# first asked for: the registry alone stays light)
_LAZY = {
    "Inpainting": ".api",
    "inpaint": ".api",
    "TransportOptions": ".transport_params",
    "SpectralOptions": ".spectral",
    "CoherenceOptions": ".coherence",
    "NavierStokesOptions": ".navier_stokes",
    "ExemplarOptions": ".exemplar",
    "StructureTextureOptions": ".structure_texture",
    "AutoOptions": ".auto",
    "PickOptions": ".pick",
}

__all__ = ["METHODS", "Method", "available", "load", "options", "register", *_LAZY]


def __getattr__(name):
    if name in _LAZY:
        return getattr(importlib.import_module(_LAZY[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
