"""PatchMatch on the device for the exemplar method (exemplar.py): one pyramid level's
planes and nearest-neighbour field, and the kernels of kernels/inpainting/patchmatch.cl that
search, score, vote and peel.

- A target is a pixel whose patch overlaps the hole; a source is a pixel whose whole patch
  lies in the box and in the known part (`valid_sources`).
- A PatchMatch pass runs every target in parallel, propagating with jumps 4, 2, 1 in the
  manner of jump flooding; the first pass of an iteration also samples at random within the
  search radius. The random numbers are a hash of (seed, pass, pixel).
- The vote fills each hole pixel from the patches covering it, weighted by
  exp(-d / 2 sigma^2) and by confidence**-depth into the hole, or from the closest patch
  alone.
- Plane counts are kernel arguments, so grey and colour images, with or without guides,
  share one program.
"""

from __future__ import annotations

import math

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from scipy import ndimage

from ..errors import InputError

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("inpainting/patchmatch.cl",)


def square_dilation(mask: np.ndarray, r: int) -> np.ndarray:
    """The pixels within r (chessboard) of `mask`: its binary dilation by a (2r + 1) square,
    as separable maxima with nothing beyond the edge (the same pixels, a tenth of the time
    of binary_dilation's erosion loop: 1.4 ms of a periodic call, stop 51)."""
    m = np.asarray(mask, bool).view(np.uint8)
    return ndimage.maximum_filter(m, size=2 * r + 1, mode="constant", cval=0).view(bool)


def valid_sources(hole: np.ndarray, r: int) -> np.ndarray:
    """Pixels whose whole patch lies in the box and in the known part."""
    valid = ~square_dilation(hole, r)
    valid[:r] = valid[-r:] = False
    valid[:, :r] = valid[:, -r:] = False
    return valid


def upsample_nnf(nnf_c: np.ndarray, shape) -> np.ndarray:
    """A fine field from a coarse one: the source of 2p + e is 2 s(p) + e."""
    H, W = shape
    y, x = np.mgrid[0:H, 0:W]
    c = nnf_c[np.minimum(y // 2, nnf_c.shape[0] - 1), np.minimum(x // 2, nnf_c.shape[1] - 1)]
    return np.stack([2 * c[..., 0] + x % 2, 2 * c[..., 1] + y % 2], -1).astype(np.int32)


class PatchMatchLevel:
    """One pyramid level of the exemplar method on the device: its planes (colours, then
    texture features, then guides), the nearest-neighbour field (NNF) of every target pixel
    (one whose patch overlaps the hole), the PatchMatch passes, the coherence sweeps and the
    votes that fill the hole from the field."""

    def __init__(
        self,
        runtime,
        dtype,
        img: np.ndarray,
        hole: np.ndarray,
        weights,
        patch: int,
        nout: int | None = None,
        radius: int | None = None,
        confidence: float = 1.0,
        ncolour: int | None = None,
    ):
        self.rt = runtime
        self.q = runtime.queue
        self.dtype = np.dtype(dtype)
        self.nch, self.H, self.W = img.shape
        self.nout = self.nch if nout is None else nout  # planes the votes fill; then guides
        self.r = patch // 2
        self.hole = hole
        # the plane count is an argument; NCH_MAX only sizes a private array, rounded up so
        # that grey and colour images, with or without guides, share one program
        defines = {"PATCH": patch, "NCH_MAX": max(8, 1 << (self.nch - 1).bit_length())}
        rt, dt = runtime, self.dtype
        self.k_pass = rt.kernel("inpainting/patchmatch.cl", "patchmatch_pass", dt, **defines)
        self.k_score = rt.kernel("inpainting/patchmatch.cl", "patchmatch_score", dt, **defines)
        self.k_vote = rt.kernel("inpainting/patchmatch.cl", "patchmatch_vote", dt, **defines)
        self.k_copy = rt.kernel("inpainting/patchmatch.cl", "patchmatch_copy_centre", dt, **defines)
        self.k_offsets = rt.kernel("inpainting/patchmatch.cl", "patchmatch_offsets", dt, **defines)
        self.ncolour = self.nch if ncolour is None else ncolour  # planes before the features
        self.chw_colour = None  # try_offsets' weights: the colours only, made when first used
        self.k_cohere = rt.kernel("inpainting/patchmatch.cl", "patchmatch_coherence", dt, **defines)

        self.valid = valid_sources(hole, self.r)
        self.valid_idx = np.flatnonzero(self.valid)
        if self.valid_idx.size == 0:
            raise InputError(
                f"the hole leaves no {patch}x{patch} patch of known pixels to copy from; "
                "use a smaller patch, a larger search region, or a structure method"
            )
        targets = square_dilation(hole, self.r)
        self.targets_mask = targets
        self.img = cla.to_device(self.q, np.ascontiguousarray(img, self.dtype))
        depth = ndimage.distance_transform_edt(hole) if confidence != 1.0 else np.zeros(hole.shape)
        self.pen = cla.to_device(self.q, (depth * math.log(confidence)).astype(self.dtype).ravel())
        self.d_valid = cla.to_device(self.q, self.valid.astype(np.uint8).ravel())
        self.d_use = cla.to_device(self.q, np.ones(self.H * self.W, np.uint8))
        self.chw = cla.to_device(self.q, np.asarray(weights, self.dtype))
        ident = np.stack(np.meshgrid(np.arange(self.W), np.arange(self.H)), -1).astype(np.int32)
        self.nnf_host = ident.reshape(-1, 2).copy()
        self.nnf = [cla.to_device(self.q, self.nnf_host), cla.to_device(self.q, self.nnf_host)]
        self.dist = cla.to_device(self.q, np.full(self.H * self.W, np.inf, self.dtype))
        self.targets = self._list(targets)
        self.targets_idx = np.flatnonzero(targets)
        self.holes = self._list(hole)
        # The random search covers the search region (the margin around the hole), not the
        # whole box: a text mask's box is the image, and samples farther than the margin
        # cost time for no PSNR (docs/inpainting_texture.md has the figures).
        widest = max(self.W, self.H)
        self.radius = max(1, min(widest, int(radius))) if radius else widest

    def _list(self, mask: np.ndarray):
        idx = np.flatnonzero(mask).astype(np.int32)
        return cla.to_device(self.q, idx if idx.size else np.zeros(1, np.int32)), idx.size

    def _launch(self, kernel, n, *args):
        if n:
            kernel(self.q, *self.rt.items(n), *args)  # a fixed work-group (Runtime.items)

    def set_nnf(self, nnf: np.ndarray, rng) -> None:
        """Upload a field for the targets, replacing sources that are not legal by random ones."""
        nnf = nnf.reshape(-1, 2).copy()
        t = np.flatnonzero(self.targets_mask)
        sx, sy = nnf[t, 0], nnf[t, 1]
        inside = (sx >= 0) & (sx < self.W) & (sy >= 0) & (sy < self.H)
        ok = np.zeros(t.size, bool)
        ok[inside] = self.valid[sy[inside], sx[inside]]
        pick = self.valid_idx[rng.integers(0, self.valid_idx.size, int((~ok).sum()))]
        bad = t[~ok]
        nnf[bad, 0], nnf[bad, 1] = pick % self.W, pick // self.W
        full = self.nnf_host.copy()
        full[t] = nnf[t]
        for buf in self.nnf:
            buf.set(full)

    def random_nnf(self, rng) -> None:
        self.set_nnf(np.full((self.H * self.W, 2), -1, np.int32), rng)

    def nnf_to_host(self) -> np.ndarray:
        return self.nnf[0].get().reshape(self.H, self.W, 2)

    def _args(self):
        return (np.int32(self.W), np.int32(self.H), np.int32(self.nch), self.chw.data)

    def patchmatch(self, passes: int, targets, masked: bool, seed: int, counter: list) -> None:
        lst, n = targets
        # The random search runs in the first pass only; the later ones propagate (jumps 2,
        # 1) what it found: the same PSNR for much less time (docs/inpainting_texture.md).
        for j in range(passes):
            jump = (4, 2, 1)[j % 3]
            self._launch(
                self.k_pass,
                n,
                self.img.data,
                self.d_use.data,
                np.int32(masked),
                self.d_valid.data,
                self.nnf[0].data,
                self.nnf[1].data,
                self.dist.data,
                lst.data,
                np.int32(n),
                *self._args(),
                np.int32(jump),
                np.int32(self.radius if j == 0 else 0),
                np.uint32(seed),
                np.uint32(counter[0]),
                np.int32(j == 0),
            )
            counter[0] += 1
            self.nnf.reverse()

    def cohere(self, sweeps: int, factor: float) -> None:
        """ICM sweeps (red, then black) that let a target take a neighbour's offset when it
        is within ``factor`` per agreeing neighbour (of 8) as good as its own
        (patchmatch_coherence; nnf[1] holds the field before each half-sweep)."""
        lst, n = self.targets
        for _ in range(sweeps):
            for parity in (0, 1):
                cl.enqueue_copy(self.q, self.nnf[1].data, self.nnf[0].data)
                self._launch(
                    self.k_cohere,
                    n,
                    self.img.data,
                    self.d_valid.data,
                    self.nnf[1].data,
                    self.nnf[0].data,
                    self.dist.data,
                    lst.data,
                    np.int32(n),
                    *self._args(),
                    np.int32(parity),
                    self.dtype.type(factor),
                )

    def try_offsets(self, offsets, targets=None, masked: bool = False) -> None:
        """Every target tries its pixel plus each of ``offsets`` (a device (n, 2) int32
        list of (dx, dy)), keeping it when its colours are at least as close
        (patchmatch_offsets)."""
        lst, n = self.targets if targets is None else targets
        if self.chw_colour is None:
            w = self.chw.get()
            w[self.ncolour :] = 0
            self.chw_colour = cla.to_device(self.q, w)
        self._launch(
            self.k_offsets,
            n,
            self.img.data,
            self.d_use.data,
            np.int32(masked),
            self.d_valid.data,
            self.nnf[0].data,
            self.dist.data,
            lst.data,
            np.int32(n),
            *self._args(),
            self.chw_colour.data,
            offsets.data,
            np.int32(offsets.size // 2),
        )

    def score(self) -> None:
        lst, n = self.targets
        self._launch(
            self.k_score,
            n,
            self.img.data,
            self.d_use.data,
            np.int32(0),
            self.nnf[0].data,
            self.dist.data,
            lst.data,
            np.int32(n),
            *self._args(),
        )

    def vote(self, best_only: bool = False, sigma2: float | None = None) -> float:
        if sigma2 is None:
            d = self.dist.get()[self.targets_idx]
            d = d[np.isfinite(d)]
            sigma2 = float(np.percentile(d, 75)) if d.size else 1.0
        sigma2 = 1.0 if sigma2 is None else sigma2
        hl, hn = self.holes
        self._launch(
            self.k_vote,
            hn,
            self.img.data,
            self.nnf[0].data,
            self.dist.data,
            self.pen.data,
            hl.data,
            np.int32(hn),
            np.int32(self.W),
            np.int32(self.H),
            np.int32(self.nch),
            np.int32(self.nout),
            self.dtype.type(max(sigma2, 1e-10)),
            np.int32(best_only),
        )
        return sigma2

    def onion_peel(self, rng, passes: int, seed: int, counter: list, offsets=None) -> None:
        """Fill the hole shell by shell from its border, matching only known neighbours;
        ``offsets``: lattice lags each shell's pixels also try (try_offsets)."""
        self.random_nnf(rng)
        depth = ndimage.distance_transform_cdt(self.hole, "chessboard")
        filled = ~self.hole
        for shell in range(1, int(depth.max()) + 1):
            layer = depth == shell
            self.d_use.set(filled.astype(np.uint8).ravel())
            lst = self._list(layer)
            self.patchmatch(passes, lst, True, seed, counter)
            if offsets is not None:
                self.try_offsets(offsets, lst, masked=True)
            self._launch(
                self.k_copy,
                lst[1],
                self.img.data,
                self.nnf[0].data,
                self.dist.data,
                lst[0].data,
                np.int32(lst[1]),
                np.int32(self.W),
                np.int32(self.H),
                np.int32(self.nout),
            )
            filled = filled | layer
        self.d_use.fill(1)

    def image(self) -> np.ndarray:
        return self.img.get()
