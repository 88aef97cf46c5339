"""Inpainting methods and their dispatch (`clpde.inpaint(..., method=..., options=...)`).

Every method is a module of this package, imported only when asked for (METHODS names
them), that registers itself with `register`:

    @register("coherence", CoherenceOptions, margin=..., soft_mask=False)
    def solve(data, omega, runtime, *, dtype=np.float32, progress=None, seed=None,
              **options) -> np.ndarray

- Options: the method's frozen dataclass, which holds its defaults and checks them on
  construction (one clear InputError line), so that a call is validated once, whoever
  builds it (`clpde.inpaint`, the command line, a batch).
- solve: called with the options object's fields as keywords, and
  - data: float (channels, rows, cols) array in [0, 1]; its values inside omega are
    irrelevant (the caller may have put anything there);
  - omega: bool (rows, cols) array, True where to fill;
  - runtime: the clpde OpenCL runtime (`clpde.runtime.get_runtime`);
  - dtype: the device's compute type (float32, or float64 with dtype=np.float64);
  - progress: None (tqdm decides), True or False: show a progress bar or not;
  - seed: for methods with randomness; the same seed gives the same result;
  - returns an array of data's shape, equal to data outside omega, a new array (data is
    not modified); any float dtype (the caller converts).
- margin: how many known pixels around omega the method reads (its stencil's reach, its
  pre-smoothing, coarse levels, patch radii...), an int or a function
  margin(omega, options) -> int. clpde.inpaint solves each connected component of the mask,
  or cluster of nearby components, in its own box: omega's bounding box grown by the margin
  (clipped to the image). A method whose result must not depend on the box sets it to
  cover everything it reads; None means the whole image: no boxes.
- align: boxes start on multiples of this (an int or align(omega, options) -> int), so
  that a multiresolution method's pyramids coincide with the whole image's.
- soft_mask: True if solve accepts `fidelity=`, a float (rows, cols) array in [0, 1)
  inside omega (1 - the mask's degree of damage; 0 = nothing known) and 0 outside. For
  other methods a soft mask m is applied afterwards as m * filled + (1 - m) * observed.
- ghost: the ghost layers of the method's device grids (the box memory check's padding).
- states: a function states(data, omega, runtime, options, *, dtype, progress, seed,
  fidelity, damage) returning a run with `states(every)`, a generator of (steps, change, data)
  along the way (what `Inpainting.iterate` shows), and afterwards `solution`, `steps`,
  `converged`, `levels`, `steps_per_level` and `band_pixels`. A method without it is run
  by its solve, as one step.
- description: one line for --help and the docs (default: the module's DESCRIPTION).

`Method` is the protocol a registered method follows; `get(name)` returns it, and
`resolve(method, options, overrides)` the method and the validated options of a call.
"""

from __future__ import annotations

import dataclasses
import importlib
import sys
from collections.abc import Callable
from typing import Protocol

from ..errors import InputError
from .runs import SolveRun
from .transport_params import TransportOptions

METHODS = {
    "transport": "clpde.inpainting.transport",
    "coherence": "clpde.inpainting.coherence",
    "navier-stokes": "clpde.inpainting.navier_stokes",
    "exemplar": "clpde.inpainting.exemplar",
    "structure-texture": "clpde.inpainting.structure_texture",
    "spectral": "clpde.inpainting.spectral",
    "pick": "clpde.inpainting.pick",
}
# method="auto": each cluster of damage is filled by the self-validated choice among
# auto.py's candidates (a method of its own, registered there).
AUTO_MODULE = "clpde.inpainting.auto"
# method=None: "pick", the frequency-selective fill ("spectral") except on the clusters of
# damage in a periodic surround, which the exemplar copies, and on thick clusters in a
# smoothly varying surround, which the biharmonic fill takes (pick.py). The spectral fill was
# chosen on the calibration half of benchmarks/inpaint_corpus.py's corpus among coherence,
# spectral and the self-validated votes, as the candidate leading the best peer in the most
# classes within a time budget of FSR-fast's, the strongest peer; "pick" ties it in every
# other class of both halves and gains ~31 dB on periodic patterns, at 1.03-1.07x its time
# (docs/inpainting.md has the tables). The votes ("auto") measured better still but several
# times slower than that budget. A call giving one of the transport's own options
# (TransportOptions: dt, max_steps, tol, ...) and no method runs the transport, and one
# giving the spectral fill's own options (SpectralOptions: iterations, block, ...) the
# spectral fill, so such calls keep their meaning.
DEFAULT = "pick"


class Method(Protocol):
    """A registered inpainting method (what `register` records and `get` returns)."""

    name: str
    options: type  # the frozen dataclass of its options
    description: str
    soft_mask: bool
    ghost: int

    def reach(self, omega, options) -> int | None:
        """Known pixels read around omega; None: the whole image."""

    def alignment(self, omega, options) -> int:
        """The multiple on which boxes start."""

    def start(self, data, omega, runtime, options, *, dtype, progress, seed, fidelity, damage):
        """The method's run on one box (`states(every)`, then `solution` and the counters)."""


@dataclasses.dataclass(frozen=True)
class Registered:
    """A method as `register` records it (follows `Method`)."""

    name: str
    options: type
    solve: Callable
    margin: int | Callable | None
    align: int | Callable
    soft_mask: bool
    ghost: int
    states: Callable | None
    description: str
    kernel_files: tuple

    def reach(self, omega, options) -> int | None:
        value = self.margin(omega, options) if callable(self.margin) else self.margin
        return None if value is None else int(value)

    def alignment(self, omega, options) -> int:
        return int(self.align(omega, options) if callable(self.align) else self.align)

    def start(self, data, omega, runtime, options, *, dtype, progress, seed, fidelity, damage):
        if self.states is not None:
            return self.states(
                data,
                omega,
                runtime,
                options,
                dtype=dtype,
                progress=progress,
                seed=seed,
                fidelity=fidelity,
                damage=damage,
            )
        return SolveRun(
            self, data, omega, runtime, options, damage, fidelity, dtype, progress, seed
        )

    def call(self, data, omega, runtime, options, **common):
        """solve with the options' fields as keywords (and `common`: dtype, progress, seed,
        fidelity)."""
        return self.solve(data, omega, runtime, **common, **keywords(options))


_REGISTERED: dict[str, Registered] = {}


def register(
    name: str,
    options: type,
    *,
    margin: int | Callable | None = None,
    align: int | Callable = 1,
    soft_mask: bool = False,
    ghost: int = 0,
    states: Callable | None = None,
    description: str | None = None,
):
    """Decorator of a method's solve: records it under `name` with its options class and
    its box geometry (the module docstring has the protocol)."""
    if not (dataclasses.is_dataclass(options) and options.__dataclass_params__.frozen):
        raise TypeError(f"{name}: options must be a frozen dataclass, not {options!r}")

    def decorate(solve: Callable) -> Callable:
        module = sys.modules.get(solve.__module__)
        _REGISTERED[name] = Registered(
            name=name,
            options=options,
            solve=solve,
            margin=margin,
            align=align,
            soft_mask=bool(soft_mask),
            ghost=int(ghost),
            states=states,
            description=description or getattr(module, "DESCRIPTION", ""),
            kernel_files=tuple(getattr(module, "KERNEL_FILES", ())),
        )
        return solve

    return decorate


def keywords(options) -> dict:
    """An options object's fields as keywords (shallow: nested options stay objects)."""
    return {f.name: getattr(options, f.name) for f in dataclasses.fields(options)}


def load(name: str):
    """The module of method `name`, imported on first use; a clear error if unknown or
    missing from this installation."""
    if not isinstance(name, str) or (name not in METHODS and name != "auto"):
        raise InputError(
            f"unknown inpainting method {name!r}; use one of {', '.join(METHODS)} or 'auto'"
        )
    path = AUTO_MODULE if name == "auto" else METHODS[name]
    try:
        return importlib.import_module(path)
    except ModuleNotFoundError as error:
        if error.name != path:
            raise
        raise InputError(
            f"inpainting method {name!r} is not available in this installation "
            f"(module {path} is missing); use one of {', '.join(available())}"
        ) from None


def get(name: str) -> Registered:
    """The registered method `name` (its module imported on first use)."""
    load(name)
    if name not in _REGISTERED:
        raise InputError(
            f"inpainting method {name!r} did not register itself (its module "
            f"{METHODS.get(name, AUTO_MODULE)} has no @register); use one of "
            f"{', '.join(available())}"
        )
    return _REGISTERED[name]


def options(name: str) -> type:
    """The options class of method `name` (a frozen dataclass of its defaults and checks)."""
    return get(name).options


def available() -> list:
    """The registered methods whose module imports."""
    names = []
    for name, path in METHODS.items():
        try:
            importlib.import_module(path)
        except ModuleNotFoundError as error:
            if error.name != path:
                raise
            continue
        names.append(name)
    return names


def resolve(method: str | None = None, options=None, overrides: dict | None = None):
    """(the registered method, its validated options) for a call.

    `options` (a method's options object) names the method by its class; with neither, the
    method is DEFAULT, or "transport" when `overrides` names one of the transport's options,
    or "spectral" when they are all the spectral fill's.
    `overrides` replace fields of the options (dataclasses.replace, so the checks run once
    on the result); a name the method lacks is one clear InputError naming its options."""
    overrides = dict(overrides or {})
    if options is not None:
        owner = method_of(type(options))
        if owner is None:
            raise InputError(
                f"options must be an inpainting method's options object (such as "
                f"clpde.inpainting.spectral.SpectralOptions), not {type(options).__name__}"
            )
        if method is not None and method != owner:
            raise InputError(
                f"options are {type(options).__name__} (method {owner!r}) but method is "
                f"{method!r}; drop one of them"
            )
        method = owner
    elif method is None:
        if set(overrides) & _names(TransportOptions):
            method = "transport"
        elif overrides and set(overrides) <= _names(get("spectral").options):
            method = "spectral"
        else:
            method = DEFAULT
    entry = get(method)
    names = _names(entry.options)
    unknown = sorted(set(overrides) - names)
    if unknown:
        raise InputError(
            f"unknown inpainting option(s) {', '.join(unknown)} for method {method!r}; "
            f"its options are {', '.join(sorted(names)) or 'none'}"
        )
    if options is None:
        options = entry.options(**overrides)
    elif overrides:
        options = dataclasses.replace(options, **overrides)
    return entry, options


def _names(options: type) -> set:
    return {f.name for f in dataclasses.fields(options)}


def method_of(options: type) -> str | None:
    """The name of the registered method whose options class this is (None if none),
    importing the methods' modules until one holds it."""
    if not dataclasses.is_dataclass(options):
        return None
    for name, entry in _REGISTERED.items():
        if entry.options is options:
            return name
    for name in (*METHODS, "auto"):
        try:
            if get(name).options is options:
                return name
        except InputError:
            continue
    return None
