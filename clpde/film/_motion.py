"""Motion-compensated neighbours of a film's frames, with the trust each warped pixel has.

Flows come from DIS (clpde.motion.dis), computed once per ordered pair of frames and kept
for the window. A neighbour's warped pixel is trusted where

- its match lies inside the neighbour's frame, with the warp's whole stencil;
- the flows agree with each other: the loop through another neighbour (t -> a, a -> b
  against t -> b: the neighbours agree along the motion, whatever frame t's own damage) and,
  at a film's ends, the neighbour's flow back (forward-backward: an occluded or revealed
  pixel has no consistent match); within a pixel or so, or within the noise once multiplied
  by the local gradient.

Everything depends only on the two frames of a pair, never on the rest of the window, so
any window or chunk of a film gives the same values, and the frames of a window can be
worked on in threads (`map_frames`: OpenCV and numpy release the GIL) in any order: each
thread has its own DIS instance, and each flow or warp is computed once, by the first
thread that asks for it. While a film runs through its sliding window (clpde.film.stream),
the detector's flows are also kept from one window to the next (`keep_flows`): a window
re-reads the frames of context the window before it held.
"""

from __future__ import annotations

import contextlib
import hashlib
import os
import threading
from collections import OrderedDict
from collections.abc import Callable, Iterable, Iterator
from concurrent.futures import Future, ThreadPoolExecutor
from dataclasses import dataclass

import numpy as np

from ..motion.dis import DisFlow, to_u8
from ._compensate import fit_gain

# Forward-backward tolerance in pixels: FB_ABS + FB_REL * |flow| (sub-pixel flows of
# textureless regions disagree by a fraction of a pixel; fast motion by more).
FB_ABS = 0.75
FB_REL = 0.1


@dataclass
class Neighbour:
    """Frame t + k brought onto frame t."""

    k: int
    grey: np.ndarray  # warped grey, flicker-corrected to frame t (H, W) float32
    inside: np.ndarray  # (H, W) bool: the match lies inside the neighbour's frame
    flow: np.ndarray  # (H, W, 2) from t to t + k
    gain: float
    offset: float


_opencv = {"lock": threading.Lock(), "users": 0, "threads": None}


@contextlib.contextmanager
def _one_opencv_thread() -> Iterator[None]:
    """OpenCV's own thread pool set to one thread while frames run in threads, and set back
    after: the frames' threads keep the cores busy already, and OpenCV's pool then only
    adds its waking and waiting (10% more CPU a frame at 640x360 on 2 cores; DIS, remap and
    the filters give the same values with any number of threads). Counted, so that calls
    from several threads at once set it back once, when the last one ends."""
    try:
        import cv2
    except ImportError:  # pragma: no cover - the film needs OpenCV (clpde.motion.dis)
        yield
        return
    with _opencv["lock"]:
        if _opencv["users"] == 0:
            _opencv["threads"] = cv2.getNumThreads()
            cv2.setNumThreads(1)
        _opencv["users"] += 1
    try:
        yield
    finally:
        with _opencv["lock"]:
            _opencv["users"] -= 1
            if _opencv["users"] == 0:
                cv2.setNumThreads(_opencv["threads"])


def map_frames(function: Callable, items: Iterable, done: Callable | None = None) -> list:
    """[function(item) for item in items], in threads (one per CPU core): a window's frames
    are independent once their flows are shared (FilmMotion), and OpenCV's and numpy's
    work runs outside the GIL (OpenCV's own pool is set to one thread meanwhile:
    _one_opencv_thread). The results come in the items' order; done(1), if given,
    is called in this thread as each comes (a progress bar, which may stop the run by
    raising: the frames not started are then cancelled)."""
    items = list(items)
    workers = min(len(items), os.cpu_count() or 1)
    results = []
    if workers <= 1:
        for item in items:
            results.append(function(item))
            if done is not None:
                done(1)
        return results
    with _one_opencv_thread(), ThreadPoolExecutor(workers) as pool:
        futures = [pool.submit(function, item) for item in items]
        try:
            for future in futures:
                results.append(future.result())
                if done is not None:
                    done(1)
        except BaseException:
            for future in futures:
                future.cancel()
            raise
    return results


def map_stacked(function: Callable, items: Iterable, keys: tuple) -> tuple[dict, list]:
    """map_frames(function, items) for a function returning a dict: the arrays under
    `keys` are copied into stacks (n, ...), in the items' threads, as each result comes
    (the first one done makes them); returns (the stacks, the results without those)."""
    items = list(items)
    stacks: dict = {}
    lock = threading.Lock()

    def one(k: int) -> dict:
        got = function(items[k])
        with lock:
            for key in keys:
                if key not in stacks:
                    stacks[key] = np.empty((len(items), *got[key].shape), got[key].dtype)
        for key in keys:
            stacks[key][k] = got.pop(key)
        return got

    return stacks, map_frames(one, range(len(items)))


class _FlowMemo:
    """Flows kept from one window of a film to the next: a block's window re-reads the
    frames of context that the window before it held, and would estimate their flows again
    from the same frames. Keyed by the DIS preset and the two frames' uint8 contents (their
    digests), so a flow is reused only for the very pair of frames it was estimated on,
    which gives it the same values (DIS depends on its two frames only). The `size` most
    recently used flows are kept while a film runs (`keep_flows`), none otherwise."""

    def __init__(self) -> None:
        self.lock = threading.Lock()
        self.kept: OrderedDict = OrderedDict()
        self.sizes: list[int] = []  # one per film running

    def get(self, key) -> np.ndarray | None:
        with self.lock:
            flow = self.kept.get(key)
            if flow is not None:
                self.kept.move_to_end(key)
            return flow

    def put(self, key, flow: np.ndarray) -> None:
        with self.lock:
            size = max(self.sizes, default=0)
            if size:
                flow.flags.writeable = False  # shared by windows: read only
                self.kept[key] = flow
            while len(self.kept) > size:
                self.kept.popitem(last=False)


_memo = _FlowMemo()


@contextlib.contextmanager
def keep_flows(size: int) -> Iterator[None]:
    """While a film runs, keep the `size` most recently used flows of the detector's
    windows for the next window (`_FlowMemo`); on leaving, drop them (once the last film
    running in the process ends: counted, and the largest size holds meanwhile)."""
    with _memo.lock:
        _memo.sizes.append(int(size))
    try:
        yield
    finally:
        with _memo.lock:
            _memo.sizes.remove(int(size))
            if not _memo.sizes:
                _memo.kept.clear()


def fb_error(f: np.ndarray, back: np.ndarray) -> np.ndarray:
    """The forward-backward check's error: |f + back|, back the return flow carried to f's
    pixels (0 where the two flows agree)."""
    return np.hypot(f[..., 0] + back[..., 0], f[..., 1] + back[..., 1])


def loop_error(fa: np.ndarray, fab: np.ndarray, fb: np.ndarray) -> np.ndarray:
    """The loop check's error: |fa + fab - fb|, t -> a -> b against t -> b directly (fab, a's
    flow to b, carried to t's pixels)."""
    return np.hypot(fa[..., 0] + fab[..., 0] - fb[..., 0], fa[..., 1] + fab[..., 1] - fb[..., 1])


class FilmMotion:
    """DIS flows between the frames of one window, and their neighbours.

    G: (T, H, W) float32 grey frames in [0, 1]; flow_grey, optional: the frames the flows
    are estimated on (the damage filled in roughly), G by default; keep: the flows go into
    the film's memo for the next window (`keep_flows`), and are read from it in any case.
    """

    def __init__(
        self, G: np.ndarray, flow_grey: np.ndarray | None = None, keep: bool = False
    ) -> None:
        self.G = G
        self.keep = keep
        self.T, self.ny, self.nx = G.shape
        src = G if flow_grey is None else flow_grey
        self.u8 = [to_u8(g) for g in src]
        self._local = threading.local()
        self._lock = threading.Lock()
        self._kept: dict = {}
        gy, gx = np.mgrid[0 : self.ny, 0 : self.nx].astype(np.float32)
        self.gx, self.gy = gx, gy

    @property
    def dis(self) -> DisFlow:
        """This thread's DIS instance (one instance's buffers are not for two threads)."""
        dis = getattr(self._local, "dis", None)
        if dis is None:
            dis = self._local.dis = DisFlow()
        return dis

    def _once(self, key, compute: Callable) -> np.ndarray:
        """compute() kept under key, computed once whichever thread asks first."""
        with self._lock:
            kept = self._kept.get(key)
            mine = kept is None
            if mine:
                kept = self._kept[key] = Future()
        if mine:
            try:
                kept.set_result(compute())
            except BaseException as exc:
                kept.set_exception(exc)
                raise
        return kept.result()

    def flow(self, t: int, s: int) -> np.ndarray:
        return self._once((t, s), lambda: self._estimate(t, s))

    def _digest(self, t: int) -> bytes:
        """Frame t's uint8 contents' digest (kept): its flows' key in the film's memo."""
        return self._once(("d", t), lambda: hashlib.blake2b(self.u8[t].data).digest())

    def _estimate(self, t: int, s: int) -> np.ndarray:
        """The flow (t, s): from the film's memo where a window before estimated it on the
        same two frames, else by DIS (and kept, for the detector's motion)."""
        if not _memo.sizes:
            return self.dis.flow(self.u8[t], self.u8[s])
        key = (self.dis.preset, self.u8[t].shape, self._digest(t), self._digest(s))
        flow = _memo.get(key)
        if flow is None:
            flow = self.dis.flow(self.u8[t], self.u8[s])
            if self.keep:
                _memo.put(key, flow)
        return flow

    def coords(self, t: int, s: int) -> tuple[np.ndarray, np.ndarray]:
        """(x + u, y + v): where frame t's pixels lie in frame s (kept: every warp along
        flow (t, s), and `inside`, read them)."""

        def compute():
            f = self.flow(t, s)
            return self.gx + f[..., 0], self.gy + f[..., 1]

        return self._once(("c", t, s), compute)

    def warp(self, image: np.ndarray, t: int, s: int, mode: str = "cubic") -> np.ndarray:
        """An image on frame s's grid (a frame, a mask, a flow; (H, W) or (H, W, C) float32)
        brought onto frame t along flow (t, s): DisFlow.warp's values."""
        xs, ys = self.coords(t, s)
        return self.dis.remap(image, xs, ys, mode)

    def warp_at(
        self, image: np.ndarray, t: int, s: int, where: np.ndarray, mode: str = "cubic"
    ) -> np.ndarray:
        """warp(image, t, s, mode)[where], warping only those pixels: (n,) or (n, C). The
        remap computes each pixel from its own coordinates, so the values are the whole
        warp's; the coordinates are laid out in rows (OpenCV takes fewer than 32767)."""
        xs, ys = self.coords(t, s)
        n = int(where.sum())
        width = 1024
        pad = np.zeros(-n % width, np.float32)
        px = np.concatenate([xs[where], pad]).reshape(-1, width)
        py = np.concatenate([ys[where], pad]).reshape(-1, width)
        out = self.dis.remap(image, px, py, mode)
        return out.reshape(-1, *image.shape[2:])[:n]

    def warped(self, t: int, s: int) -> np.ndarray:
        """Frame s's grey brought onto frame t (kept: detection and trust both read it)."""
        return self._once(("w", t, s), lambda: self.warp(self.G[s], t, s))

    def inside(self, t: int, s: int) -> np.ndarray:
        """Where frame t's match in frame s keeps the whole cubic warp's stencil (the match's
        pixel, one before and two after, in each direction) inside frame s: nearer the
        edge, the warp reads the edge's pixels repeated, a value no frame holds (kept)."""

        def compute():
            xs, ys = self.coords(t, s)
            return (xs >= 1) & (xs < self.nx - 2) & (ys >= 1) & (ys < self.ny - 2)

        return self._once(("in", t, s), compute)

    def texture(self, image: np.ndarray) -> np.ndarray:
        """The largest gradient magnitude within 2 px: how much a flow error of one pixel
        changes a compensated value there."""
        gy, gx = np.gradient(image)
        mag = np.ascontiguousarray(np.hypot(gx, gy), np.float32)
        return self.dis.cv2.dilate(mag, np.ones((5, 5), np.uint8), borderType=1)

    def trusted(self, t: int, k: int, partner: int, tol: float, fb: bool) -> np.ndarray:
        """Where neighbour t + k's compensated value is trusted: its match is inside, and the
        flows' inconsistency (the loop through t + partner; with fb also t + k's flow back),
        or its median around the pixel, is within FB_ABS + FB_REL * |flow| pixels, or
        within tol once multiplied by the local gradient (a flat region's flow may be
        loose, its compensated value is not)."""
        s, p = t + k, t + partner
        w = self.warped(t, s)
        tex = self.texture(w) + 1e-6
        err = self.loop_error(t, s, p)
        if fb:
            err = np.maximum(err, self.fb_error(t, s))
        err = np.minimum(err, self.regional(err))
        f = self.flow(t, s)
        loose = FB_ABS + FB_REL * np.hypot(f[..., 0], f[..., 1])
        return self.inside(t, s) & ((err <= loose) | (err * tex <= tol))

    def regional(self, err: np.ndarray) -> np.ndarray:
        """The median of err over about 20 px around each pixel: damage disturbs the flow
        over its own small area, and the flow of its surroundings stands for it there; an
        object the flow misses is inconsistent over its whole, larger area."""
        cv2 = self.dis.cv2
        small = cv2.resize(
            err, (max(self.nx // 4, 1), max(self.ny // 4, 1)), interpolation=cv2.INTER_AREA
        )
        small = cv2.medianBlur(np.ascontiguousarray(small, np.float32), 5)
        return cv2.resize(small, (self.nx, self.ny), interpolation=cv2.INTER_LINEAR)

    def fb_error(self, t: int, s: int) -> np.ndarray:
        return fb_error(self.flow(t, s), self.warp(self.flow(s, t), t, s, "linear"))

    def loop_error(self, t: int, a: int, b: int) -> np.ndarray:
        fab = self.warp(self.flow(a, b), t, a, "linear")
        return loop_error(self.flow(t, a), fab, self.flow(t, b))

    def gain(self, t: int, s: int) -> tuple[float, float]:
        """Frame s's flicker against frame t, fitted on the whole frame (kept: a second look
        at a window of the frame, clpde.film._reflow, keeps the whole frame's)."""
        return self._once(
            ("g", t, s), lambda: fit_gain(self.G[t], self.warped(t, s), self.inside(t, s))
        )

    def neighbour(self, t: int, k: int, fit_on: np.ndarray | None = None) -> Neighbour:
        """Frame t + k warped onto t, its flicker (a gain and offset) fitted robustly on the
        pixels whose match is inside (and fit_on, when given: pixels known clean)."""
        s = t + k
        f = self.flow(t, s)
        w = self.warped(t, s)
        ok = self.inside(t, s)
        a, b = self.gain(t, s) if fit_on is None else fit_gain(self.G[t], w, ok & fit_on)
        grey = (a * w + b).astype(np.float32)
        return Neighbour(k, grey, ok, f, a, b)
