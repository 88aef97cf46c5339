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
from ..volumes.inpaint import inpaint_volume
from . import auto, bounds, boxes, poisson
from . import registry as inpainting
from .colour import rgb_to_rho_phi_psi, rho_phi_psi_to_rgb
from .inputs import check_colour, prepare
from .runs import InpaintInfo, InpaintState


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
    device : str or int or Runtime, optional
        As for `inpaint`.
    dtype : {float32, float64}, optional
        As for `inpaint`.
    progress : bool, optional
        As for `inpaint`.
    method : str, optional
        As for `inpaint`.
    options : options object, optional
        As for `inpaint`.
    boxes : bool, optional
        As for `inpaint`.
    seed : int, optional
        As for `inpaint`.
    grow : float, optional
        As for `inpaint`.
    **overrides
        As for `inpaint`: fields of the method's options (the transport's dt, max_steps,
        tol, ...).

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
        device: DeviceLike = None,
        dtype: DTypeLike | None = None,
        progress: Progress = None,
        method: str | None = None,
        options: Any = None,
        boxes: bool = True,
        seed: int | None = None,
        grow: float = 0,
        **overrides: Any,
    ):
        # the method and its options first: a bad option fails before the image is read
        entry, self.options = inpainting.resolve(method, options, overrides)
        self.method = entry.name
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
        self.ncolour = self.planes.shape[0] - int(self.alpha)
        check_colour(colour, self.ncolour)
        if self.mask.all():
            raise InputError(
                "the mask covers every pixel, so nothing is known to inpaint from; "
                "mark only the damaged region"
            )
        self.boxes = bool(boxes)
        self.seed = seed
        self.colour = colour
        self.device = device
        self.dtype = compute_dtype(None, dtype)
        self.progress = progress
        self.result = None
        self.info = None

    @property
    def registered(self) -> inpainting.Method:
        """The method as registered (looked up, not stored, so that the object pickles)."""
        return inpainting.get(self.method)

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
        method, options = self.registered, self.options
        return boxes.boxes(
            self.mask,
            lambda crop: method.reach(crop, options),
            lambda crop: method.alignment(crop, options),
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
                ghost=self.registered.ghost,
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
            run = self.registered.start(
                data,
                omega,
                runtime,
                self.options,
                dtype=self.dtype,
                progress=self._inner_progress,
                seed=self.seed,
                fidelity=fidelity,
                damage=damage,
            )
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
            self._record(info, omega, getattr(run, "report", None))
            self._write(out, box, solved, omega, damage)
            info.omega_pixels += int(omega.sum())
            info.boxes.append(box)
            if report is not None:
                done += int(omega.sum())
                report(done, total)
        self.result = out
        self.info = info
        info.chosen = _chosen(info, self.method)
        info.build_seconds = runtime.build_seconds - built
        info.seconds = time.perf_counter() - start - info.build_seconds
        if every:
            yield InpaintState(0, info.steps, self.result)

    def _what(self) -> str:
        return f"method={self.method!r}"

    def _cold(self, runtime) -> bool:
        """Whether a program of the method (under auto: of every candidate) is not built yet
        on this runtime in this dtype."""
        if self.method == "auto":
            names = auto.candidates(self.options.names)
        else:
            names = [self.method]
        files = set()
        for name in names:
            if name == "biharmonic":
                files.update(poisson.KERNEL_FILES)
            else:
                files.update(inpainting.get(name).kernel_files)
        dt = np.dtype(self.dtype).str
        built = {(key[0], key[1]) for key in list(runtime._programs)}
        return any((f, dt) not in built for f in files)

    def _record(self, info, omega, report) -> None:
        """The box's methods in info: the method's name, or under "auto" the candidates its
        vote chose, by share of pixels (and what chose what, and why, in info.choices)."""
        if report is None:
            info.box_methods.append(self.method)
            info.box_exemplar_pixels.append(int(omega.sum()) if self.method == "exemplar" else 0)
            return
        info.choices.append(report)
        by = {}
        for choice in report["choices"]:
            by[choice["chosen"]] = by.get(choice["chosen"], 0) + choice["pixels"]
        info.box_methods.append("+".join(sorted(by, key=by.get, reverse=True)))
        info.box_exemplar_pixels.append(by.get("exemplar", 0))

    def run(self) -> np.ndarray:
        for _ in self.iterate():
            pass
        return self.result


def inpaint(
    image: ArrayLike,
    mask: ArrayLike | None = None,
    *,
    channel_axis: int | None = None,
    colour: str = "channels",
    alpha: bool | None = None,
    device: DeviceLike = None,
    dtype: DTypeLike | None = None,
    progress: Progress = None,
    snapshots: int | None = None,
    return_info: bool = False,
    method: str | None = None,
    options: Any = None,
    boxes: bool = True,
    seed: int | None = None,
    grow: float = 0,
    spacing: ArrayLike | None = None,
    **overrides: Any,
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
    colour : {'channels', 'rho-phi-psi'}, optional
        Every channel on its own, or the luminance-chroma model of thesis Figure 3.7 (3
        colour channels; any method).
    alpha : bool, optional
        Treat the last channel as alpha, passed through untouched; None means yes for
        4-channel images.
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
        clpde/inpainting/auto.py fill the hole; where they disagree, a ring of known
        pixels around the cluster is hidden and filled too, and the candidates' blend that
        their errors there weigh fills the cluster; info.choices says what chose what and
        why, info.box_methods names each box's methods by share, info.chosen the candidate
        with the largest share), 'transport' (the thesis's scheme), 'coherence',
        'navier-stokes', 'exemplar' (texture, periodic patterns), 'structure-texture' or
        'spectral' (a sparse Fourier model of each block) or 'pick' (the spectral fill,
        and the exemplar's on each cluster of damage in a periodic pattern;
        `clpde.inpainting.available()` lists what is installed). None (the default) is the
        method of `options`, else 'pick', or 'transport' when one of its options is
        among `overrides`, or 'spectral' when they are all the spectral fill's.
    options : options object, optional
        The method's options, a frozen dataclass that holds their defaults and checks:
        TransportOptions, SpectralOptions, CoherenceOptions, NavierStokesOptions,
        ExemplarOptions, StructureTextureOptions, PickOptions or AutoOptions (each in its
        method's module; `clpde.inpainting.options(method)` names the class). None: the
        method's defaults.
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
    spacing : (3,) array_like, optional
        Makes the input a (Z, Y, X) or (Z, Y, X, C) volume with this voxel size (z, y, x)
        and `mask` a (Z, Y, X) one: filled by `clpde.volumes.inpaint_volume` (method
        'biharmonic', the default, 'harmonic' or 'spectral'), which takes none of the
        planar options (a 3-D array without spacing is a colour image here).
    **overrides
        Fields of the method's options that replace those of `options` (or of the
        defaults), such as the transport's dt, max_steps, tol, mean_tol or levels
        (`TransportOptions` documents them); checked once, with the options. A name the
        method's options lack is an InputError that lists its options.

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
    >>> int(np.abs(restored.astype(int) - ramp).max()) <= 8    # pick, the default
    True
    >>> voted = clpde.inpaint(ramp, mask, method="auto")       # the self-validated choice
    >>> int(np.abs(voted.astype(int) - ramp).max()) <= 2
    True
    >>> len(info.box_methods)                           # one box of damage, one method
    1
    >>> from clpde.inpainting import TransportOptions
    >>> short = TransportOptions(max_steps=40)          # checked here, once
    >>> out, info = clpde.inpaint(ramp, mask, options=short, return_info=True, tol=0)
    >>> info.method, info.steps <= 40
    ('transport', True)
    """
    if spacing is not None:
        return _inpaint_volume(
            image,
            mask,
            channel_axis,
            method,
            spacing,
            device,
            dtype,
            progress,
            {
                "snapshots": snapshots,
                "return_info": return_info,
                "options": options,
                "seed": seed,
                "grow": grow,
                **overrides,
            },
        )
    if snapshots is not None and (
        isinstance(snapshots, bool) or not isinstance(snapshots, (int, np.integer)) or snapshots < 1
    ):
        raise InputError(f"snapshots must be a positive integer (every N steps), not {snapshots!r}")
    job = Inpainting(
        image,
        mask,
        channel_axis=channel_axis,
        alpha=alpha,
        colour=colour,
        device=device,
        dtype=dtype,
        progress=progress,
        method=method,
        options=options,
        boxes=boxes,
        seed=seed,
        grow=grow,
        **overrides,
    )
    states = list(job.iterate(every=snapshots))
    if snapshots:
        job.info.snapshots = states
    if return_info:
        return job.result, job.info
    if snapshots:
        return job.result, states
    return job.result


def _inpaint_volume(image, mask, channel_axis, method, spacing, device, dtype, progress, rest):
    """clpde.inpaint with `spacing`: a (Z, Y, X[, C]) volume, filled by clpde.volumes (whose
    methods take none of the planar options)."""
    given = sorted(k for k, v in rest.items() if v not in (None, False, 0))
    if given:
        raise InputError(
            "options for images do not apply to volumes (spacing= makes the input one): leave "
            f"out {', '.join(given)}; clpde.volumes.inpaint_volume lists a volume's options"
        )
    return inpaint_volume(
        image,
        mask,
        channel_axis,
        method=method or "biharmonic",
        spacing=spacing,
        device=device,
        dtype=dtype,
        progress=progress,
    )


def _caller_level() -> int:
    """The warnings' stacklevel of the first caller outside this module (inpaint() or
    Inpainting() alike), counted from the function that calls this one."""
    level, frame = 1, sys._getframe(1)
    while frame is not None and frame.f_code.co_filename == __file__:
        frame, level = frame.f_back, level + 1
    return level


def _chosen(info: InpaintInfo, method: str) -> str:
    """What filled the most pixels: under "auto" the candidate with the largest share of
    the votes' weights times pixels, else the method itself."""
    if method != "auto":
        return method
    share = {}
    for report in info.choices:
        for choice in report["choices"]:
            for name, weight in choice["weights"].items():
                share[name] = share.get(name, 0.0) + weight * choice["pixels"]
    return max(share, key=share.get) if share else method
