"""The docstrings' examples run, and print what they say (numpydoc `Examples` sections).

Only the modules listed here are collected: a global --doctest-modules would import every
module, the command-line package included.
"""

import doctest
import importlib

import pytest

MODULES = [
    "clpde.data",
    "clpde.planar.flows",
    "clpde.planar.rof",
    "clpde.imagedata",
    "clpde.io.images",
    "clpde.surface.implicit",
    "clpde.surface.flow_methods",
    "clpde.surface.shape_methods",
    "clpde.grid3d",
    "clpde.inpainting.colour",
    "clpde.runtime",
    "clpde.inpainting.api",
    "clpde.tracking.tracker",
    "clpde.scale.batch",
    "clpde.regions.tracker",
    "clpde.regions.api",
    "clpde.surface.render",
    "clpde.tracking.confidence",
    "clpde.film.stream",
    "clpde.film.chunks",
    "clpde.io.video_probe",
    "clpde.volumes.inpaint",
    "clpde.film._morph",
    "clpde.film._tilt",
    "clpde.film.lines",
    "clpde.film._own_lines",
    "clpde.film.fill",
    "clpde.film.detect",
    "clpde.motion.flow",
    "clpde.motion.dis",
    "clpde.io.volumes",
    "clpde.inpainting.spectral",
    "clpde.surface.inpainting",
    "clpde.surface.shapes",
]


@pytest.mark.parametrize("name", MODULES)
def test_examples_in_docstrings(name):
    module = importlib.import_module(name)
    result = doctest.testmod(module, optionflags=doctest.ELLIPSIS | doctest.NORMALIZE_WHITESPACE)
    assert result.attempted > 0, f"{name} has no examples to run"
    assert result.failed == 0, f"{result.failed} of {result.attempted} examples failed in {name}"


def test_every_public_function_listed_has_an_example():
    import clpde
    from clpde import data

    named = [
        clpde.diffuse,
        clpde.denoise_tv,
        clpde.PlanarFlow,
        clpde.stability_limit,
        clpde.devices,
        clpde.use_device,
        clpde.get_runtime,
        clpde.inpaint,
        clpde.track,
        *(
            getattr(data, n)
            for n in data.__all__
            if callable(getattr(data, n)) and not isinstance(getattr(data, n), type)
        ),
    ]
    missing = [f.__name__ for f in named if ">>>" not in (f.__doc__ or "")]
    assert not missing, f"no runnable example in the docstring of {', '.join(missing)}"
