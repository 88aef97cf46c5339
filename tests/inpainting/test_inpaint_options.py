"""One options object per inpainting method: defaults and checks in a frozen dataclass,
validated once, the same object from Python, the command line and a batch."""

import dataclasses

import numpy as np
import pytest

import clpde
from clpde import InputError
from clpde.cli.batch import command_options
from clpde.inpainting import registry
from clpde.inpainting.api import Inpainting
from clpde.scale.file_tasks import TRANSPORT_OPTIONS, inpaint_options

METHODS = (*registry.available(), "auto")


def _case(n=40):
    image = np.tile(np.linspace(0, 255, n), (n, 1)).astype(np.uint8)
    mask = np.zeros((n, n), bool)
    mask[15:22, 12:26] = True
    return image, mask


@pytest.mark.parametrize("method", METHODS)
def test_each_method_registers_a_frozen_options_class(method):
    entry = registry.get(method)
    assert entry.name == method and registry.options(method) is entry.options
    options = entry.options()  # the defaults pass their own checks
    assert dataclasses.is_dataclass(options)
    field = dataclasses.fields(options)[0].name
    with pytest.raises(dataclasses.FrozenInstanceError):
        setattr(options, field, None)
    assert registry.method_of(type(options)) == method


@pytest.mark.parametrize(
    "method,bad,match",
    [
        ("transport", {"dt": -1.0}, "dt must be"),
        ("transport", {"levels": 0}, "levels must be"),
        ("coherence", {"epsilon": 1.0}, "epsilon must be"),
        ("navier-stokes", {"steps": 0}, "steps must be"),
        ("exemplar", {"patch": 4}, "patch must be"),
        ("structure-texture", {"tv_weight": -1.0}, "tv_weight must be"),
        ("spectral", {"block": 7}, "must be even"),
        ("auto", {"ring": 0}, "ring must be"),
    ],
)
def test_bad_options_fail_on_construction_in_one_line(method, bad, match):
    with pytest.raises(InputError, match=match) as error:
        registry.options(method)(**bad)
    assert "\n" not in str(error.value)
    # and the same line from inpaint's overrides, before the image is touched
    with pytest.raises(InputError, match=match):
        clpde.inpaint(*_case(), method=method, **bad)


def test_overrides_replace_the_options_and_unknown_ones_name_the_valid():
    image, mask = _case()
    short = clpde.inpainting.TransportOptions(max_steps=30)
    a, info = clpde.inpaint(image, mask, options=short, tol=0, mean_tol=0, return_info=True)
    b = clpde.inpaint(image, mask, method="transport", max_steps=30, tol=0, mean_tol=0)
    assert info.method == "transport" and 30 <= info.steps < 40 and np.array_equal(a, b)
    assert short.tol == 1e-4  # the given object is not modified
    with pytest.raises(InputError, match=r"unknown inpainting option\(s\) radius .*'pick'"):
        clpde.inpaint(image, mask, radius=3)
    with pytest.raises(InputError, match="its options are .*block"):
        clpde.inpaint(image, mask, method="spectral", max_steps=3)
    with pytest.raises(InputError, match="drop one of them"):
        clpde.inpaint(image, mask, method="coherence", options=short)
    with pytest.raises(InputError, match="options must be an inpainting method's"):
        clpde.inpaint(image, mask, options={"dt": 0.1})


def test_the_method_follows_the_options():
    assert registry.resolve()[0].name == registry.DEFAULT
    assert registry.resolve(overrides={"dt": 0.05})[0].name == "transport"
    assert registry.resolve(overrides={"levels": 2})[0].name == "transport"
    # the default is "pick"; the spectral fill's own options with no method keep naming it
    assert registry.DEFAULT == "pick"
    assert registry.resolve(overrides={"iterations": 50})[0].name == "spectral"
    assert registry.resolve(overrides={"periodicity": 0.9})[0].name == "pick"
    spectral = clpde.inpainting.SpectralOptions(iterations=50)
    entry, options = registry.resolve(options=spectral, overrides={"border": 8})
    assert entry.name == "spectral" and options == dataclasses.replace(spectral, border=8)


def test_inpainting_validates_once_and_keeps_no_dead_state():
    image, mask = _case()
    job = Inpainting(image, mask, method="transport", levels=2)
    assert job.method == "transport" and job.options.levels == 2
    assert not hasattr(job, "p") and not hasattr(job, "levels") and not hasattr(job, "auto")


def test_each_method_has_its_own_ghost_and_margin():
    transport, spectral = registry.get("transport"), registry.get("spectral")
    assert transport.ghost == 2 and spectral.ghost == 0
    omega = np.zeros((40, 40), bool)
    omega[10:14, 10:30] = True
    wide = clpde.inpainting.TransportOptions(epsilon=6.0)
    assert transport.reach(omega, wide) > transport.reach(omega, transport.options())
    assert spectral.reach(omega, spectral.options(border=4)) == 8 + 4


def test_auto_is_a_method_and_says_what_it_chose():
    image, mask = _case()
    out, info = clpde.inpaint(image, mask, method="auto", return_info=True, progress=False)
    assert info.method == "auto"
    share = {}
    for report in info.choices:
        for choice in report["choices"]:
            for name, weight in choice["weights"].items():
                share[name] = share.get(name, 0.0) + weight * choice["pixels"]
    assert info.chosen == max(share, key=share.get)
    # a candidate's own options reach it through AutoOptions
    auto = clpde.inpainting.AutoOptions(
        names=("coherence",),
        candidate_options=(clpde.inpainting.CoherenceOptions(epsilon=3.0),),
    )
    alone = clpde.inpaint(image, mask, options=auto, progress=False)
    assert np.array_equal(alone, clpde.inpaint(image, mask, method="coherence", epsilon=3.0))
    with pytest.raises(InputError, match="not a candidate's options"):
        clpde.inpainting.AutoOptions(
            names=("coherence",), candidate_options=(clpde.inpainting.SpectralOptions(),)
        )


def _from_cli(argv):
    flags = command_options("inpaint", argv)
    keys = ("method", "levels", *TRANSPORT_OPTIONS)
    return inpaint_options(**{k: flags[k] for k in keys}, gif=bool(flags["gif"]))


def test_the_command_line_and_python_build_the_same_options():
    T = clpde.inpainting.TransportOptions
    assert _from_cli([]) == clpde.inpainting.PickOptions()  # the default, "pick"
    assert _from_cli(["--max-steps", "50", "--tol", "0"]) == T(max_steps=50, tol=0.0)
    assert _from_cli(["--gif", "evolution.gif"]) == T()  # the evolution is the transport's
    assert _from_cli(["--method", "exemplar", "--levels", "2"]) == (
        clpde.inpainting.ExemplarOptions(levels=2)
    )
    with pytest.raises(InputError, match="unknown inpainting option.*max_steps"):
        _from_cli(["--method", "coherence", "--max-steps", "5"])
