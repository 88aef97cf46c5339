"""Inpainting methods and their dispatch (`clpde.inpaint(..., method=...)`).

Every method is a module of this package, imported only when asked for, with

    solve(data, omega, runtime, *, dtype=np.float32, progress=None, seed=None, **params)
        -> np.ndarray

- data: float (channels, rows, cols) array in [0, 1]; its values inside omega are
  irrelevant (the caller may have put anything there).
- omega: bool (rows, cols) array, True where to fill.
- runtime: the clpde OpenCL runtime (`clpde.runtime.get_runtime`).
- dtype: the device's compute type (float32, or float64 with dtype=np.float64).
- progress: None (tqdm decides), True or False: show a progress bar or not.
- seed: for methods with randomness; the same seed gives the same result.
- params: the method's own keyword options. Unknown names are turned into an InputError
  by the dispatch, from solve's signature, before solve runs.
- returns: an array of data's shape, equal to data outside omega, a new array (data is
  not modified); any float dtype (the caller converts).

Optional module attributes:

- MARGIN: int, or a function MARGIN(omega, **params) -> int (or MARGIN(**params)). How
  many known pixels around omega the method reads (its stencil's reach, its pre-smoothing,
  coarse levels, patch radii...). clpde.inpaint solves each connected component of the mask, or
  cluster of nearby components, in its own box: omega's bounding box grown by MARGIN
  (clipped to the image). A method whose result must not depend on the box sets it to
  cover everything it reads; None (or no attribute) means the whole image: no boxes.
- SOFT_MASK: True if solve accepts `fidelity=`, a float (rows, cols) array in [0, 1)
  inside omega (1 - the mask's degree of damage; 0 = nothing known) and 0 outside. For
  other methods a soft mask m is applied afterwards as m * filled + (1 - m) * observed.
- DESCRIPTION: one line for --help and the docs.
- run: a function of solve's arguments returning a run with `states(every)`, a generator of
  (steps, change, data) along the way (what `Inpainting.iterate` shows), and afterwards
  `solution`, `steps`, `converged`, `levels`, `steps_per_level` and `band_pixels`. A method
  without it is run by its solve, as one step.
"""

from __future__ import annotations

import importlib
import inspect

from ..errors import InputError
from .transport_params import InpaintParams

METHODS = {
    "transport": "clpde.inpainting.transport",
    "coherence": "clpde.inpainting.coherence",
    "navier-stokes": "clpde.inpainting.navier_stokes",
    "exemplar": "clpde.inpainting.exemplar",
    "structure-texture": "clpde.inpainting.structure_texture",
    "spectral": "clpde.inpainting.spectral",
}

# method=None: "auto", except that a call giving any of the transport's own options
# (InpaintParams: dt, max_steps, tol, ...) runs the transport, so such calls keep their meaning.
# method="auto": each cluster of damage is filled by the self-validated choice among
# validate.py's candidates; the options a call gives go to the first of these that is
# installed.
AUTO = ("coherence", "transport")
# method=None: the frequency-selective fill. Chosen on the calibration half of
# benchmarks/inpaint_corpus.py's corpus among coherence, spectral and the self-validated votes,
# as the candidate leading the best peer in the most classes within a time budget of
# FSR-fast's, the strongest peer (docs/inpainting.md has the tables). The votes ("auto")
# measured better still but several times slower than that budget.
DEFAULT = "spectral"
COMMON = ("dtype", "progress", "seed")  # keywords every solve takes, passed by the dispatch


def load(name: str):
    """The module of method `name`, imported on first use; a clear error if unknown or
    missing from this installation."""
    if not isinstance(name, str) or name not in METHODS:
        raise InputError(
            f"unknown inpainting method {name!r}; use one of {', '.join(METHODS)} or 'auto'"
        )
    path = METHODS[name]
    try:
        return importlib.import_module(path)
    except ModuleNotFoundError as error:
        if error.name != path:
            raise
        raise InputError(
            f"inpainting method {name!r} is not available in this installation "
            f"(module {path} is missing); use one of {', '.join(available())}"
        ) from None


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


def check_params(name: str, module, params: dict) -> None:
    """InputError for options that `module.solve` does not take."""
    sig = inspect.signature(module.solve)
    if any(p.kind is p.VAR_KEYWORD for p in sig.parameters.values()):
        return
    accepted = {n for n, p in sig.parameters.items() if p.kind is p.KEYWORD_ONLY} - set(COMMON)
    unknown = sorted(set(params) - accepted)
    if unknown:
        raise InputError(
            f"unknown inpainting option(s) {', '.join(unknown)} for method {name!r}; "
            f"its options are "
            f"{', '.join(sorted(accepted)) or 'none'}"
        )


def margin(module, omega, params: dict):
    """The method's margin in pixels for this omega, or None for the whole image."""
    value = getattr(module, "MARGIN", None)
    if callable(value):
        takes_omega = "omega" in inspect.signature(value).parameters
        value = value(omega, **params) if takes_omega else value(**params)
    return None if value is None else int(value)


def soft(module) -> bool:
    return bool(getattr(module, "SOFT_MASK", False))


def choose_method(omega, method: str | None, params=(), per_box=False) -> str:
    """The method to run. None is DEFAULT, unless `params` holds one of the transport's own
    options (InpaintParams), when it is "transport" (the thesis's scheme); "auto" is the
    first installed of AUTO, which takes the options given, while each cluster of damage is
    filled by the self-validated choice (inpainting/validate.py). per_box=True returns
    "auto" itself in that case."""

    if method is None:  # levels too: the transport's multiresolution
        transport_only = {"levels", *InpaintParams.__dataclass_fields__}
        method = "transport" if set(params) & transport_only else DEFAULT
    if method == "auto" and per_box:
        return method
    if method == "auto":
        installed = available()
        return next(name for name in AUTO if name in installed)
    load(method)  # a clear error for unknown or missing ones
    return method
