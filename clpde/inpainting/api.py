"""`clpde.inpaint` and `clpde.Inpainting`: the method's choice and the boxes, for every
inpainting method alike (the input's checks and scaling are inputs.py's; the states and the
report of a run, runs.py's).

- Methods: `method=` picks one of clpde.inpainting's modules through the registry
  (registry.py); the thesis's scheme is "transport" (transport.py), one method among the
  others. The dispatch, the boxes and the soft masks are shared by all of them.
- Boxes: each connected component of the mask, or cluster of nearby components, is solved
  in its own box, its bounding box grown by the method's margin (clpde/inpainting/boxes.py);
  only the box is converted to float, so time and memory follow the damage. The output
  is one copy of the input, written in place, box by box.
- The data is scaled to [0, 1] for the methods; the output equals the input bit for bit
  outside the mask, in the input's dtype.
"""

from __future__ import annotations

import inspect
import sys
import time
import warnings
from collections.abc import Iterator
from typing import Any

import numpy as np
from numpy.typing import ArrayLike, DTypeLike

from .._progress import Progress, on_terminal
from ..errors import InputError
from ..fields import check_fits
from ..imagedata import compute_dtype, grow_mask, growth
from ..runtime import DeviceLike, get_runtime
from . import bounds, boxes, poisson, validate
from . import registry as inpainting
from .colour import rgb_to_rho_phi_psi, rho_phi_psi_to_rgb
from .inputs import check_colour, prepare
from .registry import choose_method, margin
from .runs import InpaintInfo, InpaintState, SolveRun
from .transport_params import _TRANSPORT_ARGS, GHOST, transport_params
from .transport_params import check_params as check_transport_params


class Inpainting:
    """Inpainting whose intermediate states can be watched.

    `iterate(every)` yields the states (from method="transport" only; other methods yield
    their start and their result); afterwards `result` and `info` are set. `run()` runs to
    the end and returns the result.

    Parameters
    ----------
    image : array_like
        As for `inpaint`.
    mask : array_like, optional
        As for `inpaint`.
    channel_axis : int, optional
        As for `inpaint`.
    alpha : bool, optional
        As for `inpaint`.
    colour : {'channels', 'rho-phi-psi'}, optional
        As for `inpaint`.
    levels : int, optional
        As for `inpaint`.
    device : str or int or Runtime, optional
        As for `inpaint`.
    dtype : {float32, float64}, optional
        As for `inpaint`.
    progress : bool, optional
        As for `inpaint`.
    method : str, optional
        As for `inpaint`.
    boxes : bool, optional
        As for `inpaint`.
    seed : int, optional
        As for `inpaint`.
    grow : float, optional
        As for `inpaint`.
    **params
        The method's options, as `inpaint`'s (the transport's dt, max_steps, tol, ...).

    Raises
    ------
    InputError
        For an image, mask, method or option that cannot be used.

    Examples
    --------
    >>> import numpy as np
    >>> ramp = np.tile(np.linspace(0, 1, 32, dtype=np.float32), (32, 1))
    >>> mask = np.zeros((32, 32), bool)
    >>> mask[12:20, 12:20] = True
    >>> job = Inpainting(ramp, mask, method="transport")
    >>> steps = [state.step for state in job.iterate(every=50)]   # show(state.image) ...
    >>> steps[0] < steps[-1], job.result.shape, job.info.converged
    (True, (32, 32), True)
    """

    def __init__(
        self,
        image: ArrayLike,
        mask: ArrayLike | None = None,
        *,
        channel_axis: int | None = None,
        alpha: bool | None = None,
        colour: str = "channels",
        levels: int | None = None,
        device: DeviceLike = None,
        dtype: DTypeLike | None = None,
        progress: Progress = None,
        method: str | None = None,
        boxes: bool = True,
        seed: int | None = None,
        grow: float = 0,
        **params: Any,
    ):

        self.image, self.planes, self.mask, self.softness, self.layout, self.alpha = prepare(
            image, mask, channel_axis, alpha
        )
        if growth(grow) > 0:  # (no copy of the mask otherwise: it may be image-sized)
            if self.softness is not None:  # a soft mask grows its support, fully damaged
                self.softness = grow_mask(self.softness, grow)
                self.mask = self.softness > 0
            else:
                self.mask = grow_mask(self.mask, grow)
        if not self.mask.any():
            warnings.warn(
                "the mask is empty, so nothing was filled and the image comes back "
                "unchanged; was the mask inverted or saved blank?",
                UserWarning,
                stacklevel=_caller_level(),
            )
        ncolour = self.planes.shape[0] - int(self.alpha)
        check_colour(colour, ncolour)
        if self.mask.all():
            raise InputError(
                "the mask covers every pixel, so nothing is known to inpaint from; "
                "mark only the damaged region"
            )
        if levels is not None and (
            isinstance(levels, bool) or not isinstance(levels, (int, np.integer)) or levels < 1
        ):
            raise InputError(f"levels must be an integer >= 1 or None (automatic), not {levels!r}")
        given = {**params, **({} if levels is None else {"levels": levels})}
        self.method = choose_method(self.mask, method, given)
        # "auto" votes per cluster of damage among inpainting/validate.py's candidates; the
        # options given are this structure method's.
        self.auto = choose_method(self.mask, method, given, per_box=True) == "auto"
        if self.method == "transport":
            self.p = transport_params(params)
            check_transport_params(self.p)
            check_colour(colour, ncolour)
            if levels is not None:
                params = dict(params, levels=levels)
        else:
            self.p = None
            if levels is not None:
                params = dict(params, levels=levels)
            inpainting.check_params(self.method, self.module, params)
        self.params = params
        self.boxes = bool(boxes)
        self.seed = seed
        self.colour = colour
        self.ncolour = ncolour
        self.levels = levels
        self.device = device
        self.dtype = compute_dtype(None, dtype)
        self.progress = progress
        self.result = None
        self.info = None

    @property
    def module(self):
        """The method's module (looked up, not stored, so that the object pickles)."""

        return inpainting.load(self.method)

    # -- conversions between the user's image and the solved channels -----------------
    def _box_data(self, box, model=True):
        """The box's channels as float64 in [0, 1] (NaN -> 0), colour model applied (unless
        `model` is False)."""
        y0, y1, x0, x1 = box
        part = self.planes[: self.ncolour, y0:y1, x0:x1]
        data = (part.astype(np.float64) - self.layout.offset) / self.layout.scale
        if np.issubdtype(part.dtype, np.floating):
            data[~np.isfinite(data)] = 0.0
        return rgb_to_rho_phi_psi(data) if model and self.colour == "rho-phi-psi" else data

    def _write(self, out, box, solved, omega, damage=None):
        """Omega's colour channels of the box from the solution, each held within the range
        of the known pixels around its cluster (bounds.py; the colour hull is left to the
        methods that need it, navier-stokes: its cost per cluster shows on dust, and on the
        calibration half it gained nothing for the others); everything else of `out` stays
        the input's, bit for bit."""
        y0, y1, x0, x1 = box
        colour = rho_phi_psi_to_rgb(solved) if self.colour == "rho-phi-psi" else solved
        colour = bounds.limit(colour, self._box_data(box, model=False), omega, damage, hull=False)
        values = colour[:, omega] * self.layout.scale + self.layout.offset
        if self.layout.dtype == bool:  # a binary image stays binary: cut at one half
            values = values > 0.5
        elif np.issubdtype(self.layout.dtype, np.integer):
            info = np.iinfo(self.layout.dtype)
            values = np.clip(np.rint(values), info.min, info.max)
        view = (
            out[np.newaxis]
            if self.layout.channel_axis is None
            else np.moveaxis(out, self.layout.channel_axis, 0)
        )
        view[: self.ncolour, y0:y1, x0:x1][:, omega] = values.astype(self.layout.dtype)

    def _boxes(self):

        ny, nx = self.mask.shape
        if not self.boxes:
            return [(0, ny, 0, nx)]
        if self.auto:  # every candidate, and the ring it is scored on, fits in the box
            return boxes.boxes(self.mask, lambda crop: validate.margin(crop=crop))
        align = getattr(self.module, "ALIGN", None)
        return boxes.boxes(
            self.mask,
            lambda crop: margin(self.module, crop, self.params),
            (lambda crop: align(crop, **self.params)) if callable(align) else lambda crop: 1,
        )

    def iterate(self, every: int | None = None) -> Iterator[InpaintState]:
        """Run to the end, yielding an InpaintState at the start of the finest level, every
        `every` steps there (rounded to whole check intervals) and at the end. Coarser
        levels run without yielding. Afterwards `result` and `info` are set."""

        start = time.perf_counter()
        out = self.image.copy()
        if not self.mask.any():
            self.result = out
            self.info = InpaintInfo(0, True, 0, method=None)
            yield InpaintState(0, 0, self.result)
            return
        runtime = get_runtime(self.device)
        built = runtime.build_seconds
        if self._cold(runtime) and (
            self.progress is True or (self.progress is None and on_terminal())
        ):
            # a first use builds the method's programs (seconds on a CPU device): say why
            # it waits; the time is left out of info.seconds
            print(
                f"clpde: building kernels (once) for {self._what()}...", file=sys.stderr, flush=True
            )
        info = InpaintInfo(0, True, 0, method=self.method)
        boxes = self._boxes()
        # Each box's finest level keeps the ping-pong pair, prev and known, the one-channel
        # weight and three index lists on the device: every box is checked before any work.
        for y0, y1, x0, x1 in boxes:
            check_fits(
                runtime,
                (self.ncolour, y1 - y0, x1 - x0),
                "inpainting",
                4 + 4 / self.ncolour,
                ghost=GHOST,
                dtype=self.dtype,
            )
        # A callable progress hears masked pixels done over all to do, once per box; the
        # methods' own step counts would mix units, so inside a box they only repeat the
        # last figure (which is where a caller's cancel gets its chance to raise).
        report = self.progress if callable(self.progress) else None
        done, total = (
            0,
            sum(int(np.count_nonzero(self.mask[y0:y1, x0:x1])) for y0, y1, x0, x1 in boxes),
        )
        self._inner_progress = self.progress if report is None else (lambda *_: report(done, total))
        for box in boxes:
            y0, y1, x0, x1 = box
            omega = np.array(self.mask[y0:y1, x0:x1], bool)
            data = self._box_data(box)
            damage = (
                None
                if self.softness is None
                else np.asarray(self.softness[y0:y1, x0:x1], np.float64)
            )
            fidelity = None if damage is None else np.where(omega, 1.0 - damage, 0.0)
            if self.auto:
                # the self-validated choice among the candidates (inpainting/validate.py)
                solved = self._voted_box(runtime, data, omega, info)
                if damage is not None:
                    solved = np.where(omega, damage * solved + (1 - damage) * data, data)
                info.levels = max(info.levels, 1)
            else:
                info.box_methods.append(self.method)
                info.box_exemplar_pixels.append(
                    int(omega.sum()) if self.method == "exemplar" else 0
                )
                run = self._run(runtime, data, omega, fidelity, damage)
                for steps, change, solved in run.states(every):
                    self._write(out, box, solved, omega, damage)
                    yield InpaintState(0, info.steps + steps, out.copy(), change)
                solved = run.solution
                info.steps = max(info.steps, run.steps)
                info.converged &= run.converged
                info.levels = max(info.levels, run.levels)
                if run.steps_per_level:
                    info.steps_per_level = run.steps_per_level
                info.band_pixels += run.band_pixels
            self._write(out, box, solved, omega, damage)
            info.omega_pixels += int(omega.sum())
            info.boxes.append(box)
            if report is not None:
                done += int(omega.sum())
                report(done, total)
        self.result = out
        self.info = info
        info.build_seconds = runtime.build_seconds - built
        info.seconds = time.perf_counter() - start - info.build_seconds
        if every:
            yield InpaintState(0, info.steps, self.result)

    def _what(self) -> str:
        return "method='auto'" if self.auto else f"method={self.method!r}"

    def _cold(self, runtime) -> bool:
        """Whether a program of the method (under auto: of every candidate) is not built yet
        on this runtime in this dtype."""
        names = validate.candidates() if self.auto else [self.method]
        files = set()
        for name in names:
            module = poisson if name == "biharmonic" else inpainting.load(name)
            files.update(getattr(module, "KERNEL_FILES", ()))
        dt = np.dtype(self.dtype).str
        built = {(key[0], key[1]) for key in list(runtime._programs)}
        return any((f, dt) not in built for f in files)

    def _run(self, runtime, data, omega, fidelity, damage):
        """The method's run on one box: its own `run` when it has one (states along the
        way), else its `solve` as one step (registry.py has the protocol)."""
        if hasattr(self.module, "run"):
            return self.module.run(
                data,
                omega,
                runtime,
                dtype=self.dtype,
                progress=self._inner_progress,
                seed=self.seed,
                fidelity=fidelity,
                **self.params,
            )
        return SolveRun(
            self.module,
            data,
            omega,
            runtime,
            damage,
            fidelity,
            dtype=self.dtype,
            progress=self._inner_progress,
            seed=self.seed,
            **self.params,
        )

    def _voted_box(self, runtime, data, omega, info):
        """The box filled by the self-validated choice (inpainting/validate.py); what chose
        what, and why, goes to info.choices."""
        params = {self.method: self.params} if self.params else {}
        solved, report = validate.choose(
            data, omega, runtime, dtype=self.dtype, seed=self.seed, params=params
        )
        info.choices.append(report)
        by = {}
        for choice in report["choices"]:
            by[choice["chosen"]] = by.get(choice["chosen"], 0) + choice["pixels"]
        info.box_methods.append("+".join(sorted(by, key=by.get, reverse=True)))
        info.box_exemplar_pixels.append(by.get("exemplar", 0))
        return solved

    def run(self) -> np.ndarray:
        for _ in self.iterate():
            pass
        return self.result


def inpaint(
    image: ArrayLike,
    mask: ArrayLike | None = None,
    *,
    channel_axis: int | None = None,
    dt: float = 0.1,
    transport_steps: int = 15,
    diffusion_steps: int = 2,
    diffusion_dt: float = 0.1,
    epsilon: float = 3.0,
    presmooth: int = 1,
    scaling: str = "none",
    rotation: str = "ccw",
    max_steps: int = 3000,
    tol: float = 1e-4,
    mean_tol: float = 4e-4,
    check_every: int = 2,
    levels: int | None = None,
    colour: str = "channels",
    alpha: bool | None = None,
    fill: str = "biharmonic",
    keep_band: bool = True,
    device: DeviceLike = None,
    dtype: DTypeLike | None = None,
    progress: Progress = None,
    snapshots: int | None = None,
    return_info: bool = False,
    method: str | None = None,
    boxes: bool = True,
    seed: int | None = None,
    grow: float = 0,
    **options: Any,
) -> np.ndarray | tuple[np.ndarray, InpaintInfo] | tuple[np.ndarray, list[InpaintState]]:
    """Fill the masked region of an image.

    Parameters
    ----------
    image : array_like
        2-D greyscale, or 3-D with `channel_axis` (any number of channels); uint8, uint16,
        other integers or floats of any range (scaled to [0, 1] internally), or bool (a
        binary image: filled as 0/1 and cut at one half, so it comes back bool).
    mask : array_like, optional
        (rows, columns). bool or integer: nonzero where to inpaint. float: the degree of
        damage in [0, 1], 1 unknown, 0 known; a pixel in between keeps a fidelity (1 - m)
        to its observed value (a soft mask, applied after every A + B cycle of the
        transport, after the fill for other methods). None fills the NaN pixels of a float
        image.
    channel_axis : int, optional
        The axis of the channels; None for a greyscale image.
    dt : float, optional
        Transport: the time step.
    transport_steps : int, optional
        Transport: A, the transport steps of a cycle.
    diffusion_steps : int, optional
        Transport: B, the anisotropic diffusion steps of a cycle.
    diffusion_dt : float, optional
        Transport: the diffusion's time step (<= 0.25; appendix A's code uses 0.2, the text
        0.1).
    epsilon : float, optional
        Transport: width of the band Omega-epsilon around Omega (>= 2 pixels).
    presmooth : int, optional
        Transport: steps of anisotropic diffusion of the box before the loop.
    scaling : {'none', 'quartic-root'}, optional
        Transport: eq. (3.6) as printed, or appendix A's sign(I_t) |I_t|^(1/4) on its
        0..255 scale, which keeps faint structures moving but never settles (the run then
        usually ends at max_steps).
    rotation : {'ccw', 'cw'}, optional
        Transport: the rotation of the gradient (the steady state is the same).
    max_steps : int, optional
        Transport: steps per level at most.
    tol : float, optional
        Transport: stop once the largest change inside Omega over `check_every` cycles is
        below it ([0, 1] units; 0 turns the test off).
    mean_tol : float, optional
        Transport: stop once the mean change there is below it (the test that ends runs on
        photos, where a few pixels never settle; docs/inpainting.md).
    check_every : int, optional
        Transport: cycles of A + B steps between the checks, made on the device.
    levels : int, optional
        Resolution levels; None picks them per box from the mask's thickness
        (multiresolution.auto_levels).
    colour : {'channels', 'rho-phi-psi'}, optional
        Every channel on its own, or the luminance-chroma model of thesis Figure 3.7 (3
        colour channels; any method).
    alpha : bool, optional
        Treat the last channel as alpha, passed through untouched; None means yes for
        4-channel images.
    fill : {'biharmonic', 'diffusion', 'mean', 'zero'}, optional
        Transport: the start inside Omega on the coarsest level (the best PSNR on photos
        comes early, so the start matters; docs/inpainting.md compares them).
    keep_band : bool, optional
        Transport: reset the known pixels of Omega-epsilon after each diffusion batch, or
        let the diffusion keep smoothing them (False).
    device : str or int or Runtime, optional
        The OpenCL device, as for `clpde.use_device`.
    dtype : {float32, float64}, optional
        The device's arithmetic (float32 by default).
    progress : bool or callable, optional
        Draw a progress bar; by default only for long runs on a terminal. A callable
        ``progress(done, total)`` hears the masked pixels filled so far and in all, after
        each box, and may stop the run by raising.
    snapshots : int, optional
        Also keep the intermediate states (InpaintState) every N steps of the finest level.
    return_info : bool, optional
        Also return an InpaintInfo (steps taken, whether it converged, the boxes, ...).
    method : str, optional
        'auto' (self-validated, per cluster of damage: the candidate methods of
        clpde/inpainting/validate.py fill the hole; where they disagree, a ring of known
        pixels around the cluster is hidden and filled too, and the blend of the candidates
        that fits that ring best fills the cluster; info.choices says what chose what and
        why, info.box_methods names each box's methods by share), 'transport' (the thesis's
        scheme, the options above), 'coherence', 'navier-stokes', 'exemplar' (texture,
        periodic patterns), 'structure-texture' or 'spectral' (a sparse Fourier model of
        each block; `clpde.inpainting.available()` lists what is installed).
        None (the default) is 'spectral', or 'transport' when a transport option is given.
    boxes : bool, optional
        Solve each connected component of the mask, or cluster of nearby components, in
        its own box grown by the method's margin, so that time and memory follow the
        damage; False solves the whole image at once (the same results, bit for bit where
        each run takes the same number of steps).
    seed : int, optional
        For methods with randomness.
    grow : float, optional
        Grow the mask by a disc of this radius in pixels first (`clpde.grow_mask`; a soft
        mask's grown ring is fully damaged), to take in a damage's blurred rim. 0: as given.
        An empty mask (nothing to fill) warns and returns a copy, with ``info.method`` None.
    **options
        The other methods' options, and the transport's `stencil` ('isotropic', Scharr's
        derivatives, or appendix A's 'central') and `coarse_start` ('corrected' or
        'upsampled').

    Returns
    -------
    image : ndarray
        The input's shape and dtype, equal to it bit for bit outside the mask; by default
        alone, `(image, info)` with return_info (info.snapshots then holds the states, if
        asked for), `(image, [InpaintState, ...])` with snapshots and without return_info.
        `Inpainting` is the object form with the same keywords.

    Raises
    ------
    InputError
        For an image, mask, method or option that cannot be used; the message names the fix.

    Examples
    --------
    >>> import numpy as np
    >>> import clpde
    >>> ramp = np.tile(np.linspace(0, 255, 48), (48, 1)).astype(np.uint8)
    >>> mask = np.zeros((48, 48), bool)
    >>> mask[18:30, 18:30] = True
    >>> restored, info = clpde.inpaint(ramp, mask, return_info=True)
    >>> restored.dtype, restored.shape
    (dtype('uint8'), (48, 48))
    >>> bool((restored[~mask] == ramp[~mask]).all())   # untouched outside the mask
    True
    >>> int(np.abs(restored.astype(int) - ramp).max()) <= 8    # spectral, the default
    True
    >>> voted = clpde.inpaint(ramp, mask, method="auto")       # the self-validated choice
    >>> int(np.abs(voted.astype(int) - ramp).max()) <= 2
    True
    >>> len(info.box_methods)                           # one box of damage, one method
    1
    """
    given = locals()  # the transport options are InpaintParams' fields, named alike here
    transport = {name: given[name] for name in _TRANSPORT_ARGS}
    if snapshots is not None and (
        isinstance(snapshots, bool) or not isinstance(snapshots, (int, np.integer)) or snapshots < 1
    ):
        raise InputError(f"snapshots must be a positive integer (every N steps), not {snapshots!r}")
    # Only the transport options the caller changed are passed on: the defaults are those
    # of InpaintParams, and another method rejects a transport option it lacks by name.
    defaults = inspect.signature(inpaint).parameters
    params = {k: v for k, v in transport.items() if not _same(v, defaults[k].default)}
    params.update(options)
    job = Inpainting(
        image,
        mask,
        channel_axis=channel_axis,
        alpha=alpha,
        colour=colour,
        levels=levels,
        device=device,
        dtype=dtype,
        progress=progress,
        method=method,
        boxes=boxes,
        seed=seed,
        grow=grow,
        **params,
    )
    states = list(job.iterate(every=snapshots))
    if snapshots:
        job.info.snapshots = states
    if return_info:
        return job.result, job.info
    if snapshots:
        return job.result, states
    return job.result


def _caller_level() -> int:
    """The warnings' stacklevel of the first caller outside this module (inpaint() or
    Inpainting() alike), counted from the function that calls this one."""
    level, frame = 1, sys._getframe(1)
    while frame is not None and frame.f_code.co_filename == __file__:
        frame, level = frame.f_back, level + 1
    return level


def _same(value, default) -> bool:
    return type(value) is type(default) and value == default
