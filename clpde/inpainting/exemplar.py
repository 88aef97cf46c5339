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
- Before that last vote, a few ICM sweeps over the offsets (patchmatch_coherence): a pixel takes a
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
from dataclasses import asdict, dataclass

import numpy as np
import pyopencl.array as cla
from scipy import ndimage

from .._progress import progress_bar
from ..errors import InputError
from . import coherence
from . import stitch as _stitch
from .choose import MIN_PERIODICITY, lattice_offsets, periodicity
from .patchmatch import PatchMatchLevel, upsample_nnf, valid_sources
from .registry import register


@dataclass(frozen=True)
class ExemplarOptions:
    """method="exemplar"'s options (the module docstring; solve's docstring has their
    meaning), checked on construction."""

    patch: int = 7  # patch side, odd
    search: int = 128  # search region around the hole's box, in pixels of the finest level
    iterations: int = 6  # EM iterations (PatchMatch, then vote) at the coarsest level
    fine_iterations: int = 3  # at each finer level, which starts from the coarser field
    passes: int = 3  # PatchMatch passes per iteration (jumps 4, 2, 1)
    # weight of the texture features in the distance; 0: off; None: automatic
    features: float | None = None
    levels: int | None = None  # pyramid levels; None chooses from the hole's thickness
    onion_passes: int = 4  # PatchMatch passes per shell of the coarsest level's onion peel
    sharpen: bool = True  # the last vote takes the closest patch's value (else the weighted mean)
    # vote weights times confidence**-depth into the hole (Wexler et al.); 1: off
    confidence: float = 1.3
    # re-solve the final fill from its sources' gradients (stitch.py), so copied regions
    # meet without a jump in tone
    stitch: bool = True
    # weight of a structure guide: the coherence fill of the hole, compared in the patch
    # distance so that patches continue the edges that cross the hole; 0: none
    # None: automatic, 1 unless the hole's surroundings are periodic (choose.periodicity)
    structure: float | None = None
    # before the finest level's last vote, ICM sweeps over the offsets: a target takes a
    # neighbour's offset when its patch distance is within this factor per agreeing
    # neighbour of its own, so that copied regions are larger and seams fewer; 1: off
    cohere: float = 1.5
    cohere_sweeps: int = 4
    # where the hole's surroundings are periodic (choose.periodicity), the targets also try
    # the lattice's lags (choose.lattice_offsets) in the onion peel and before the last
    # vote, so that the field takes the lattice's phase whatever the seed
    lattice: bool = True

    def __post_init__(self) -> None:
        _check(self)


def MARGIN(omega=None, search=ExemplarOptions.search, **_params) -> int:
    """Context pixels the method needs around a hole component: its search region."""
    return int(search)


def _params(params: dict) -> dict:
    """The options as a dict, checked (ExemplarOptions)."""
    return asdict(ExemplarOptions(**params))


def _check(p: ExemplarOptions) -> None:
    patch = p.patch
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
        v = getattr(p, name)
        if not isinstance(v, (int, np.integer)) or v < (0 if name == "search" else 1):
            raise InputError(f"{name} must be a positive integer, not {v!r}")
    levels = p.levels
    if levels is not None and (not isinstance(levels, (int, np.integer)) or levels < 1):
        raise InputError(f"levels must be a positive integer or None (automatic), not {levels!r}")
    g = p.confidence
    if not isinstance(g, (int, float, np.floating, np.integer)) or not np.isfinite(g) or g < 1:
        raise InputError(f"confidence must be a number >= 1 (1 turns it off), not {g!r}")
    sw = p.structure
    if sw is not None and (
        not isinstance(sw, (int, float, np.floating, np.integer)) or not np.isfinite(sw) or sw < 0
    ):
        raise InputError(
            f"structure must be a weight >= 0 (0 turns it off) or None (automatic), not {sw!r}"
        )
    g = p.cohere
    if not isinstance(g, (int, float, np.floating, np.integer)) or not np.isfinite(g) or g < 1:
        raise InputError(f"cohere must be a number >= 1 (1 turns it off), not {g!r}")
    f = p.features
    if f is not None and (
        not isinstance(f, (int, float, np.floating, np.integer)) or not np.isfinite(f) or f < 0
    ):
        raise InputError(f"features must be a weight >= 0 (0 turns them off), not {f!r}")


DEFAULTS = asdict(ExemplarOptions())


# ---------------------------------------------------------------------------------------
# Host-side preparation, per level (proportional to the box, not the image)


# The structure guide's coherence for holes deeper than GUIDE_DEPTH px: a stronger pull
# along the coherence direction (kappa 100 for the fill's 25), so that edges entering a
# thick hole are carried further before the isotropic mean takes over; it scores higher on
# the thick and texture cases (docs/inpainting_texture.md), while thinner holes (text,
# scratches) keep the fill's defaults.
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


def _periodic(colour: np.ndarray, hole: np.ndarray) -> bool:
    """Whether the hole's near surroundings repeat (choose.periodicity, on the hole's box
    grown by 24 px)."""

    near = _box(hole, 24)
    return periodicity(colour[(slice(None),) + near], hole[near]) >= MIN_PERIODICITY


def _lattice_offsets(lv: PatchMatchLevel, colour: np.ndarray, hole: np.ndarray):
    """The lags at which this level's known colours repeat, on the device; None if none."""

    lags = lattice_offsets(colour, hole)
    return cla.to_device(lv.q, np.ascontiguousarray(lags, np.int32)) if lags.size else None


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
        if min(h.shape) < patch + 2 or not valid_sources(h, r).any():
            break  # a level with nothing to copy from would only guess
        if g is not None:  # guides are known everywhere: plain 2 x 2 means
            g = _downsample(g, np.zeros(g.shape[1:], bool))[0]
        pyramid.append((c, h, g))
    return pyramid


@register("exemplar", ExemplarOptions, margin=lambda omega, o: MARGIN(omega, o.search))
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
    nlevels = p["levels"] or _levels_for(hole, patch // 2, hole.shape)
    pyramid = _pyramid(colour, hole, guides, patch, nlevels)
    p.update(sharpen=bool(sharpen), stitch=stitch, lattice=lattice and periodic)
    result = _descend(pyramid, runtime, dtype, p, rng, seed, progress)
    filled = out[(slice(None),) + box]
    filled[:, hole] = result[: data.shape[0]][:, hole].astype(out.dtype)
    return out


def _level(runtime, dtype, level, nc: int, fw: float, p: dict) -> PatchMatchLevel:
    """A pyramid level (colour, hole, guides) on the device: its colours, the texture
    features weighted by `fw` (their planes are filled by the votes too), then the guides,
    which only enter the patch distance."""
    c, h, g = level
    patch = int(p["patch"])
    planes, w = [c], [1.0] * nc
    if fw > 0:
        planes.append(texture_features(c, h, patch))
        w += [fw * nc / 2] * 2
    nout = sum(len(x) for x in planes)
    if g is not None:
        planes.append(g)
        w += [1.0] * len(g)
    return PatchMatchLevel(
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


def _descend(pyramid, runtime, dtype, p: dict, rng, seed: int, progress) -> np.ndarray:
    """The finest level's planes, filled coarse to fine: the coarsest level starts by onion
    peel, each finer one from the coarser field upsampled, then EM iterations (PatchMatch,
    then vote); the last vote may be stitched (stitch.py)."""
    nc = pyramid[0][0].shape[0]
    # Automatic feature weight: 1 when the hole needs a pyramid. A hole thin enough for one
    # level (text, scratches) has most of each target patch known, so colours alone tell
    # texture from smooth, and the features would cost time for little gain.
    fw = float(p["features"]) if p["features"] is not None else (1.0 if len(pyramid) > 1 else 0.0)
    counter = [0]
    prev_nnf = None
    bar = progress_bar(progress, len(pyramid), "exemplar levels", leave=False)
    for level in range(len(pyramid) - 1, -1, -1):
        c, h, _ = pyramid[level]
        lv = _level(runtime, dtype, pyramid[level], nc, fw, p)
        # A level started from the coarser field needs fewer iterations than the coarsest;
        # so does a single level (a thin hole), whose onion peel is already at full
        # resolution (docs/inpainting_texture.md has the measurements).
        coarse_start = prev_nnf is None and len(pyramid) > 1
        its = int(p["iterations"] if coarse_start else p["fine_iterations"])
        # the lattice's lags: in the onion peel (the phase the levels start from) and before
        # the last vote (the sources the stitch reads); the levels between keep the phase
        needed = p["lattice"] and (prev_nnf is None or level == 0)
        offsets = _lattice_offsets(lv, c, h) if needed else None
        if prev_nnf is None:
            lv.onion_peel(rng, int(p["onion_passes"]), seed, counter, offsets)
            lv.set_nnf(lv.nnf_to_host(), rng)
        else:
            lv.set_nnf(upsample_nnf(prev_nnf, h.shape), rng)
            lv.score()
            lv.vote()
        for it in range(its):
            lv.patchmatch(int(p["passes"]), lv.targets, False, seed, counter)
            last = level == 0 and it == its - 1
            # At the last iteration only: as good as at every iteration of the finest level,
            # for less time.
            if last and p["cohere"] > 1:
                lv.cohere(int(p["cohere_sweeps"]), float(p["cohere"]))
            if offsets is not None and last:
                # before the last vote, whose sources the stitch reads beyond their patches
                lv.try_offsets(offsets)
            sigma2 = lv.vote(best_only=p["sharpen"] and last)
        prev_nnf = lv.nnf_to_host()
        bar.update()
    bar.close()
    result = lv.image()
    if p["stitch"] and p["sharpen"]:
        h, r = pyramid[0][1], int(p["patch"]) // 2
        src = _stitch.vote_sources(
            prev_nnf,
            lv.dist.get().reshape(h.shape),
            lv.pen.get().reshape(h.shape),
            h,
            r,
            sigma2,
        )
        result[:nc] = _stitch.stitch(result[:nc], h, src, r)
    return result
