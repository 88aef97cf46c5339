"""Inpainting: `clpde.inpaint` and `clpde.Inpainting` (api.py), the method registry
(registry.py) and one module per method, each with its frozen options class (imported on
first use: ``from clpde.inpainting import SpectralOptions``)."""

import importlib

from .registry import METHODS, Method, available, load, options, register

# each method's options class -> its module (imported when the name is first asked for)
_OPTIONS = {
    "TransportOptions": ".transport_params",
    "SpectralOptions": ".spectral",
    "CoherenceOptions": ".coherence",
    "NavierStokesOptions": ".navier_stokes",
    "ExemplarOptions": ".exemplar",
    "StructureTextureOptions": ".structure_texture",
    "AutoOptions": ".validate",
    "PickOptions": ".pick",
}

__all__ = ["METHODS", "Method", "available", "load", "options", "register", *_OPTIONS]


def __getattr__(name):
    if name in _OPTIONS:
        return getattr(importlib.import_module(_OPTIONS[name], __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
