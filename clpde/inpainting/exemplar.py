"""Exemplar (patch-based) inpainting on the device, after Wexler, Shechtman and Irani (2007)
and Newson, Almansa, Gousseau and Perez (IPOL 2017).

The hole is filled with pieces of the image around it, so texture comes back as texture
rather than as a smooth average. The method minimises the sum, over every patch that
overlaps the hole, of the distance to its nearest patch in the known part:

- An image pyramid (2 x 2 averages of the known pixels; a coarse pixel is in the hole when
  any pixel under it is), with as many levels as bring the hole's half-thickness down to
  about a patch radius.
- At each level, alternate a few times (6 at the coarsest level, 3 at the finer ones, which
  start from a good field): nearest-neighbour fields (NNF) by PatchMatch (all targets in
  parallel on the device: three passes propagating with jumps 4, 2, 1 in the manner of jump
  flooding, the first with a random search); then each hole pixel from the votes of the patches
  covering it, weighted by exp(-d / 2 sigma^2), sigma^2 the 75th percentile of the distances.
- Texture features (local averages of |dI/dx| and |dI/dy| of the grey image, over a patch)
  are extra planes in the patch distance, reconstructed with the colours: without them a
  smooth patch is a good match for a textured one whose mean colour it shares, and holes in
  texture come back smooth.
- The coarsest level starts by onion peel: shell by shell from the border inwards, each
  pixel takes the centre of the patch that best matches its already known neighbours.
  A finer level starts from the coarser NNF, upsampled (offsets doubled), and a vote, so
  that its detail comes from real fine-scale patches.
- Before that last vote, a few ICM sweeps over the offsets (pm_coherence): a pixel takes a
  neighbour's offset when its patch distance is within a small factor per agreeing
  neighbour of its own, so that copied regions are larger and their seams fewer.
- Periodic surroundings (choose.periodicity): the lags at which the known part repeats
  (choose.lattice_offsets) are offsets that every target also tries, in the onion peel
  and before the last vote (after the sweeps), keeping one when its colours match at
  least as well (ties go to the lattice). A flat patch of a periodic pattern matches many
  phases; which one the random search found depended on the seed, and the stitch, which
  reads the source's neighbours beyond the patch, turned a wrong phase into a visible
  error.
- The last vote at the finest level takes, for each pixel, the closest patch's value only;
  a weighted mean of slightly misaligned patches blurs the texture that the method exists
  to keep.

Work is on the box of the hole grown by ``search`` pixels (the search region, which is also
``MARGIN``): the cost of an iteration is proportional to the number of pixels whose patch
overlaps the hole, and the random search covers the box. The random numbers are a hash of
(seed, pass, pixel): a seed gives the same result on every run and device.
"""

from __future__ import annotations

import math

import numpy as np
import pyopencl as cl
import pyopencl.array as cla
from scipy import ndimage

from .._progress import progress_bar
from ..errors import InputError
from . import coherence
from . import stitch as _stitch
from .choose import MIN_PERIODICITY, lattice_offsets, periodicity

DEFAULTS = {
    "patch": 7,  # patch side, odd
    "search": 128,  # search region around the hole's box, in pixels of the finest level
    "iterations": 6,  # EM iterations (PatchMatch, then vote) at the coarsest level
    "fine_iterations": 3,  # at each finer level, which starts from the coarser field
    "passes": 3,  # PatchMatch passes per iteration (jumps 4, 2, 1)
    "features": None,  # weight of the texture features in the distance; 0: off; None: automatic
    "levels": None,  # pyramid levels; None chooses from the hole's thickness
    "onion_passes": 4,  # PatchMatch passes per shell of the coarsest level's onion peel
    "sharpen": True,  # the last vote takes the closest patch's value (else the weighted mean)
    # vote weights times confidence**-depth into the hole (Wexler et al.); 1: off
    "confidence": 1.3,
    # re-solve the final fill from its sources' gradients (stitch.py), so copied regions
    # meet without a jump in tone
    "stitch": True,
    # weight of a structure guide: the coherence fill of the hole, compared in the patch
    # distance so that patches continue the edges that cross the hole; 0: none
    # None: automatic, 1 unless the hole's surroundings are periodic (choose.periodicity)
    "structure": None,
    # before the finest level's last vote, ICM sweeps over the offsets: a target takes a
    # neighbour's offset when its patch distance is within this factor per agreeing
    # neighbour of its own, so that copied regions are larger and seams fewer; 1: off
    "cohere": 1.5,
    "cohere_sweeps": 4,
    # where the hole's surroundings are periodic (choose.periodicity), the targets also try
    # the lattice's lags (choose.lattice_offsets) in the onion peel and before the last
    # vote, so that the field takes the lattice's phase whatever the seed
    "lattice": True,
}
KERNEL_FILES = ("inpainting/patchmatch.cl",)


def MARGIN(omega=None, search=DEFAULTS["search"], **_params) -> int:
    """Context pixels the method needs around a hole component: its search region."""
    return int(search)


def _params(params: dict) -> dict:
    p = {**DEFAULTS, **params}
    patch = p["patch"]
    if not isinstance(patch, (int, np.integer)) or patch < 3 or patch % 2 == 0:
        raise InputError(f"patch must be an odd integer >= 3 (the patch side), not {patch!r}")
    for name in (
        "search",
        "iterations",
        "fine_iterations",
        "passes",
        "onion_passes",
        "cohere_sweeps",
    ):
        v = p[name]
        if not isinstance(v, (int, np.integer)) or v < (0 if name == "search" else 1):
            raise InputError(f"{name} must be a positive integer, not {v!r}")
    levels = p["levels"]
    if levels is not None and (not isinstance(levels, (int, np.integer)) or levels < 1):
        raise InputError(f"levels must be a positive integer or None (automatic), not {levels!r}")
    g = p["confidence"]
    if not isinstance(g, (int, float, np.floating, np.integer)) or not np.isfinite(g) or g < 1:
        raise InputError(f"confidence must be a number >= 1 (1 turns it off), not {g!r}")
    sw = p["structure"]
    if sw is not None and (
        not isinstance(sw, (int, float, np.floating, np.integer)) or not np.isfinite(sw) or sw < 0
    ):
        raise InputError(
            f"structure must be a weight >= 0 (0 turns it off) or None (automatic), not {sw!r}"
        )
    g = p["cohere"]
    if not isinstance(g, (int, float, np.floating, np.integer)) or not np.isfinite(g) or g < 1:
        raise InputError(f"cohere must be a number >= 1 (1 turns it off), not {g!r}")
    f = p["features"]
    if f is not None and (
        not isinstance(f, (int, float, np.floating, np.integer)) or not np.isfinite(f) or f < 0
    ):
        raise InputError(f"features must be a weight >= 0 (0 turns them off), not {f!r}")
    return p


# ---------------------------------------------------------------------------------------
# Host-side preparation, per level (proportional to the box, not the image)


# The structure guide's coherence for holes deeper than GUIDE_DEPTH px: a stronger pull
# along the coherence direction (kappa 100 for the fill's 25), so that edges entering a
# thick hole are carried further before the isotropic mean takes over. Seeds 0-2 of the
# exemplar: thick 22.21 -> 22.36 dB (kappa 50: see docs, 200: 21.89), texture 20.48 ->
# 20.62; thinner holes (text, scratches) keep the fill's defaults.
GUIDE_DEPTH = 8
GUIDE_KAPPA = 100.0


def _guide_params(hole: np.ndarray) -> dict:
    deep = ndimage.distance_transform_edt(np.pad(hole, 1)).max() > GUIDE_DEPTH
    return {"kappa": GUIDE_KAPPA} if deep else {}


def _box(omega: np.ndarray, margin: int):
    rows = np.flatnonzero(omega.any(axis=1))
    cols = np.flatnonzero(omega.any(axis=0))
    ny, nx = omega.shape
    return (
        slice(max(rows[0] - margin, 0), min(rows[-1] + 1 + margin, ny)),
        slice(max(cols[0] - margin, 0), min(cols[-1] + 1 + margin, nx)),
    )


def _downsample(img: np.ndarray, hole: np.ndarray):
    """2 x 2 means of the known pixels; a coarse pixel is in the hole when any fine one is."""
    nc, ny, nx = img.shape
    py, px = ny % 2, nx % 2
    known = np.pad(~hole, ((0, py), (0, px)), mode="edge").astype(img.dtype)
    vals = np.pad(img, ((0, 0), (0, py), (0, px)), mode="edge") * known
    h2, w2 = known.shape[0] // 2, known.shape[1] // 2
    k = known.reshape(h2, 2, w2, 2).sum(axis=(1, 3))
    v = vals.reshape(nc, h2, 2, w2, 2).sum(axis=(2, 4))
    coarse_hole = k < 4
    return np.where(k > 0, v / np.maximum(k, 1), 0).astype(img.dtype), coarse_hole


def texture_features(img: np.ndarray, hole: np.ndarray, patch: int) -> np.ndarray:
    """Local means of |dI/dx| and |dI/dy| of the grey image over a patch, known pixels only.

    Differences that touch the hole are left out of the means (their values are not known
    yet); inside the hole the features are filled by the votes along with the colours.
    """
    grey = img.mean(axis=0)
    known = ~hole
    out = np.zeros((2,) + grey.shape, img.dtype)
    for axis in (1, 0):
        d = np.abs(np.diff(grey, axis=axis))
        ok = known[:, 1:] & known[:, :-1] if axis == 1 else known[1:] & known[:-1]
        pad = ((0, 0), (0, 1)) if axis == 1 else ((0, 1), (0, 0))
        d = np.pad(np.where(ok, d, 0), pad)
        w = np.pad(ok, pad).astype(np.float64)
        num = ndimage.uniform_filter(d.astype(np.float64), patch, mode="nearest")
        den = ndimage.uniform_filter(w, patch, mode="nearest")
        out[1 - axis if axis == 1 else 1] = np.where(den > 1e-6, num / np.maximum(den, 1e-6), 0)
    return out


def _valid_sources(hole: np.ndarray, r: int) -> np.ndarray:
    """Pixels whose whole patch lies in the box and in the known part."""
    bad = ndimage.binary_dilation(hole, structure=np.ones((2 * r + 1, 2 * r + 1), bool))
    valid = ~bad
    valid[:r] = valid[-r:] = False
    valid[:, :r] = valid[:, -r:] = False
    return valid


def _levels_for(hole: np.ndarray, r: int, shape) -> int:
    depth = ndimage.distance_transform_cdt(np.pad(hole, 1, constant_values=False), "chessboard")
    # The 99th percentile of the hole pixels' depth, not the maximum: a text mask's strokes
    # cross at a few deeper pixels, and a coarse level for those costs time and PSNR.
    depth = float(np.percentile(depth[depth > 0], 99))
    levels = 1 + max(0, math.ceil(math.log2(max(depth, 1) / r)))
    # Keep the coarsest box a few patches wide, or there is nothing left to copy from.
    while levels > 1 and min(shape) / 2 ** (levels - 1) < 4 * (2 * r + 1):
        levels -= 1
    return levels


# ---------------------------------------------------------------------------------------
# One level on the device


class _Level:
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
        self.k_pass = rt.kernel("inpainting/patchmatch.cl", "pm_pass", dt, **defines)
        self.k_score = rt.kernel("inpainting/patchmatch.cl", "pm_score", dt, **defines)
        self.k_vote = rt.kernel("inpainting/patchmatch.cl", "pm_vote", dt, **defines)
        self.k_copy = rt.kernel("inpainting/patchmatch.cl", "pm_copy_centre", dt, **defines)
        self.k_offsets = rt.kernel("inpainting/patchmatch.cl", "pm_offsets", dt, **defines)
        self.ncolour = self.nch if ncolour is None else ncolour  # planes before the features
        self.chw_colour = None  # try_offsets' weights: the colours only, made when first used
        self.k_cohere = rt.kernel("inpainting/patchmatch.cl", "pm_coherence", dt, **defines)

        self.valid = _valid_sources(hole, self.r)
        self.valid_idx = np.flatnonzero(self.valid)
        if self.valid_idx.size == 0:
            raise InputError(
                f"the hole leaves no {patch}x{patch} patch of known pixels to copy from; "
                "use a smaller patch, a larger search region, or a structure method"
            )
        targets = ndimage.binary_dilation(hole, structure=np.ones((2 * self.r + 1,) * 2, bool))
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
        # cost 20% of a searching pass for no PSNR (measured on the texture and thick cases).
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
        # 1) what it found. Measured: the same PSNR on the thick holes (19.91 against 19.88
        # dB, mean of 3 seeds) for 41% less CPU time on a 10% text mask.
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
        (pm_coherence; nnf[1] holds the field before each half-sweep)."""
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
        list of (dx, dy)), keeping it when its colours are at least as close (pm_offsets)."""
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


def _periodic(colour: np.ndarray, hole: np.ndarray) -> bool:
    """Whether the hole's near surroundings repeat (choose.periodicity, on the hole's box
    grown by 24 px)."""

    near = _box(hole, 24)
    return periodicity(colour[(slice(None),) + near], hole[near]) >= MIN_PERIODICITY


def _lattice_offsets(lv: _Level, colour: np.ndarray, hole: np.ndarray):
    """The lags at which this level's known colours repeat, on the device; None if none."""

    lags = lattice_offsets(colour, hole)
    return cla.to_device(lv.q, np.ascontiguousarray(lags, np.int32)) if lags.size else None


def _upsample_nnf(nnf_c: np.ndarray, shape) -> np.ndarray:
    """A fine field from a coarse one: the source of 2p + e is 2 s(p) + e."""
    H, W = shape
    y, x = np.mgrid[0:H, 0:W]
    c = nnf_c[np.minimum(y // 2, nnf_c.shape[0] - 1), np.minimum(x // 2, nnf_c.shape[1] - 1)]
    return np.stack([2 * c[..., 0] + x % 2, 2 * c[..., 1] + y % 2], -1).astype(np.int32)


# ---------------------------------------------------------------------------------------


def _guides(data, colour, hole, box, runtime, dtype, guide, structure, lattice):
    """(guide planes of the box or None, whether its surroundings are periodic): the user's
    guide, and the coherence fill of the hole weighted by `structure` (automatic: 1, or 0
    where the surroundings repeat)."""
    guides = None
    if guide is not None:
        guide = np.asarray(guide, np.float64)
        guide = guide[None] if guide.ndim == 2 else guide
        if guide.shape[1:] != data.shape[1:]:
            raise InputError(
                f"guide has shape {guide.shape}; give (planes, {data.shape[1]}, "
                f"{data.shape[2]}) planes known everywhere, the hole included"
            )
        guides = guide[(slice(None),) + box]
    periodic = _periodic(colour, hole) if structure is None or lattice else False
    if structure is None:
        # Automatic: the guide, unless the surroundings repeat (periodic texture, stripes),
        # where copies can be exact and a smooth fill would pull them away (choose.py).
        sw = 0.0 if periodic else 1.0
    else:
        sw = float(structure)
    if sw > 0:
        filled = coherence.solve(colour, hole, runtime, dtype=dtype, **_guide_params(hole))
        guides = sw * filled if guides is None else np.concatenate([guides, sw * filled])
    return guides, periodic


def _pyramid(colour, hole, guides, patch, nlevels):
    """[(colour, hole, guides)] from fine to coarse, while a level has sources to copy."""
    r = patch // 2
    pyramid = [(colour, hole, guides)]
    for _ in range(nlevels - 1):
        c, h, g = pyramid[-1]
        c, h = _downsample(c, h)
        if min(h.shape) < patch + 2 or not _valid_sources(h, r).any():
            break  # a level with nothing to copy from would only guess
        if g is not None:  # guides are known everywhere: plain 2 x 2 means
            g = _downsample(g, np.zeros(g.shape[1:], bool))[0]
        pyramid.append((c, h, g))
    return pyramid


def solve(
    data,
    omega,
    runtime,
    *,
    dtype=np.float32,
    progress=None,
    seed=None,
    patch=DEFAULTS["patch"],
    search=DEFAULTS["search"],
    iterations=DEFAULTS["iterations"],
    fine_iterations=DEFAULTS["fine_iterations"],
    passes=DEFAULTS["passes"],
    features=DEFAULTS["features"],
    levels=None,
    onion_passes=DEFAULTS["onion_passes"],
    sharpen=DEFAULTS["sharpen"],
    confidence=DEFAULTS["confidence"],
    guide=None,
    stitch=DEFAULTS["stitch"],
    structure=DEFAULTS["structure"],
    cohere=DEFAULTS["cohere"],
    cohere_sweeps=DEFAULTS["cohere_sweeps"],
    lattice=DEFAULTS["lattice"],
):
    """Fill ``omega`` in ``data`` ((channels, rows, cols) in [0, 1]) with patches of the rest.

    Parameters (all optional): patch (7), search (128 px of context around the hole's box),
    iterations (6 at the coarsest level), fine_iterations (3 at each finer one), passes (3
    PatchMatch passes per iteration), features (weight of the texture features; 0 turns
    them off; default 1 when the hole needs a pyramid, 0 for a thin one), levels (automatic),
    onion_passes (4), sharpen (True: the last vote takes the closest patch), confidence
    (1.3: vote weights times confidence**-depth into the hole; 1 turns it off), guide
    (extra (k, rows, cols) planes, known everywhere, that enter the patch distance but are
    not filled, e.g. an inpainted structure image), structure (weight of the coherence
    fill of the hole as such a guide, so that edges crossing the hole are continued; None,
    the default: 1, or 0 where the hole's surroundings are periodic),
    stitch (True: re-solve the last vote's fill from its sources' gradients, stitch.py),
    cohere (factor >= 1 of the coherence sweeps before the finest level's last vote; 1
    turns them off) and cohere_sweeps (their number),
    lattice (True: on periodic surroundings, the targets also try the lattice's lags).
    ``seed`` (default 0) fixes the random search.
    Returns a new array; only ``omega`` differs from ``data``.
    """
    p = _params(
        {
            "patch": patch,
            "search": search,
            "iterations": iterations,
            "fine_iterations": fine_iterations,
            "passes": passes,
            "features": features,
            "levels": levels,
            "onion_passes": onion_passes,
            "confidence": confidence,
            "structure": structure,
            "cohere": cohere,
            "cohere_sweeps": cohere_sweeps,
        }
    )
    data = np.asarray(data)
    omega = np.asarray(omega, bool)
    out = np.array(data, copy=True)
    if not omega.any():
        return out
    if omega.all():
        raise InputError("the mask covers the whole image: there is nothing to copy patches from")
    seed = 0 if seed is None else int(seed)
    rng = np.random.default_rng(seed)
    patch = int(p["patch"])
    r = patch // 2
    nc = data.shape[0]

    box = _box(omega, MARGIN(omega, p["search"]))
    hole = omega[box]
    colour = np.asarray(data[(slice(None),) + box], np.float64).copy()
    colour[:, hole] = 0  # values there are unknown, may be NaN, and are never read
    guides, periodic = _guides(data, colour, hole, box, runtime, dtype, guide, structure, lattice)
    if min(hole.shape) < patch + 2:
        raise InputError(
            f"the region around the hole ({hole.shape[0]}x{hole.shape[1]} px) is smaller than "
            f"a {patch}x{patch} patch; use a smaller patch"
        )

    nlevels = p["levels"] or _levels_for(hole, r, hole.shape)
    pyramid = _pyramid(colour, hole, guides, patch, nlevels)

    # Automatic feature weight: 1 when the hole needs a pyramid. A hole thin enough for one
    # level (text, scratches) has most of each target patch known, so colours alone tell
    # texture from smooth: on a 10% text mask the features cost 25% of the time for 0.1 dB.
    fw = float(p["features"]) if p["features"] is not None else (1.0 if len(pyramid) > 1 else 0.0)
    counter = [0]
    prev_nnf = None
    bar = progress_bar(progress, len(pyramid), "exemplar levels", leave=False)
    for level in range(len(pyramid) - 1, -1, -1):
        c, h, g = pyramid[level]
        planes, w = [c], [1.0] * nc
        if fw > 0:
            planes.append(texture_features(c, h, patch))
            w += [fw * nc / 2] * 2
        nout = sum(len(x) for x in planes)
        if g is not None:
            planes.append(g)
            w += [1.0] * len(g)
        lv = _Level(
            runtime,
            dtype,
            np.concatenate(planes),
            h,
            w,
            patch,
            nout,
            radius=int(p["search"]),
            confidence=float(p["confidence"]),
            ncolour=nc,
        )
        # A level started from the coarser field needs fewer iterations than the coarsest;
        # so does a single level (a thin hole), whose onion peel is already at full
        # resolution: on a 10% text mask 3 iterations instead of 6 cost 0.3 dB and a third
        # of the time.
        coarse_start = prev_nnf is None and len(pyramid) > 1
        its = int(p["iterations"] if coarse_start else p["fine_iterations"])
        # the lattice's lags: in the onion peel (the phase the levels start from) and before
        # the last vote (the sources the stitch reads); the levels between keep the phase
        needed = lattice and periodic and (prev_nnf is None or level == 0)
        offsets = _lattice_offsets(lv, c, h) if needed else None
        if prev_nnf is None:
            lv.onion_peel(rng, int(p["onion_passes"]), seed, counter, offsets)
            lv.set_nnf(lv.nnf_to_host(), rng)
        else:
            lv.set_nnf(_upsample_nnf(prev_nnf, h.shape), rng)
            lv.score()
            lv.vote()
        for it in range(its):
            lv.patchmatch(int(p["passes"]), lv.targets, False, seed, counter)
            last = level == 0 and it == its - 1
            # Measured (thick holes, mean of seeds 0-2): at the last iteration only, the
            # same as at every iteration of the finest level, for less time.
            if last and p["cohere"] > 1:
                lv.cohere(int(p["cohere_sweeps"]), float(p["cohere"]))
            if offsets is not None and last:
                # before the last vote, whose sources the stitch reads beyond their patches
                lv.try_offsets(offsets)
            sigma2 = lv.vote(best_only=bool(sharpen) and last)
        prev_nnf = lv.nnf_to_host()
        bar.update()
        if level == 0:
            result = lv.image()
            if stitch and sharpen:
                src = _stitch.vote_sources(
                    prev_nnf,
                    lv.dist.get().reshape(h.shape),
                    lv.pen.get().reshape(h.shape),
                    h,
                    r,
                    sigma2,
                )
                result[:nc] = _stitch.stitch(result[:nc], h, src, r)
    bar.close()
    filled = out[(slice(None),) + box]
    filled[:, hole] = result[:nc][:, hole].astype(out.dtype)
    return out
