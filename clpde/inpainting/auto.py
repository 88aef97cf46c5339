"""Self-validation: what `method="auto"` fills each cluster of damage with, measured there.

Which method fills a hole best depends on the hole and on what surrounds it, and a rule
fitted to named cases learns those cases. Here each box of damage measures it instead:

1. Every candidate method fills the box's hole.
2. The hole's pixels are grouped into clusters: the connected components of the hole grown
   by the ring's width (so components closer than two ring widths share one cluster, and
   one ring). Where the candidates' fills of a cluster agree (their largest RMS difference
   from the cluster's mean fill is below AGREE, half an 8-bit quantisation step), no vote
   is run there: such a cluster takes the box's vote (AGREED), step 4.
3. For the clusters that disagree, a ring of known pixels around them is hidden as well,
   and every candidate fills the grown hole once. Its error on the ring, whose truth is
   known, is its score in that cluster. Each cluster's ring is as wide as SCALE times its
   hole's half-thickness, between RING and RING_MAX px: a thin ring around a thick hole
   only tells which fill is smoothest near the border. With NARROW a second ring, RING px
   around every cluster, is hidden and filled on its own too: a wide ring makes the hole
   thicker than it is, a narrow one tests only the border, and the hole's pixels lie at
   every depth between.
4. Each cluster gets a blend of the candidates' fills, by a soft vote: each candidate's
   weight is (e_min / e_k) ** POWER, e_k its mean squared error on the ring (POWER 0: the
   least-squares blend, as before stop 49; `blend=False` keeps the single best
   candidate), pulled towards the weights of every voting ring of the box at once, as if
   those added PRIOR values to the cluster's own: a speck of dust's ring holds a few
   dozen values. With two rings, each votes so, and the cluster takes the mean of the
   weights. The clusters that did not vote take the mean over the rings of the box's.

The candidate set, the ring's widths, the prior and blend or pick are the module's
parameters; all were chosen on the calibration half of benchmarks/inpaint_corpus.py's
corpus (benchmarks/inpaint_validate_calibrate.py for the candidates,
benchmarks/inpaint_vote_rules.py and benchmarks/inpaint_vote_sound.py for the rest;
docs/inpainting.md has the tables), and nothing else was fitted. `choices` in the returned
report says, per cluster, what was chosen, with which weights, and why. The vote is not
yet sound on every case: docs/inpainting.md ("A soft vote") has the cases that still fall
more than 0.2 dB below their best candidate on each half.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, optimize

from ..errors import InputError
from . import poisson
from .registry import METHODS, available, get, keywords, load, method_of, register

# The candidates, cheapest first (the first one fills clusters where all agree), and the
# narrowest ring of known pixels hidden to score them: chosen on the calibration half
# (the candidates: benchmarks/inpaint_validate_calibrate.py --quick, the best mean PSNR over
# the classes; RING: benchmarks/inpaint_vote_rules.py --ring 1 against 2, fewer cases below
# the best candidate, 11 of 62 against 18; docs/inpainting.md has the tables)
CANDIDATES = ("biharmonic", "coherence", "navier-stokes", "exemplar", "spectral")
RING = 1
# A cluster's weights are its own ring's vote pulled towards the vote of every voting ring
# of the box, as if the box's ring added PRIOR values to the cluster's own: a speck of
# dust's ring holds a few dozen values. 100 with the soft vote (POWER; 1000 with the
# least-squares blend): chosen with POWER on the calibration half
# (benchmarks/inpaint_vote_sound.py --real; docs/inpainting.md, "A soft vote").
PRIOR = 100.0
# A ring as thin as RING tells how well a candidate fills a thin hole: a smooth fill always
# wins there, and loses deep in a thick hole. Each cluster's ring is as wide as SCALE times
# its hole's half-thickness (its deepest pixel's distance to the known ones), between RING
# and RING_MAX pixels; SCALE 0: RING for every cluster.
SCALE = 0.5
RING_MAX = 8
# NARROW: a second test beside that ring: a ring of RING px around every cluster, its own
# fill; each cluster's weights are the mean of the two tests' votes. The narrow ring
# favours the fills that are good near the border (smooth ones), the wide ring those good
# deeper in (the texture ones); neither alone is unbiased for a hole's pixels, which lie
# at every depth from 1 px to its half-thickness. Chosen on the calibration half
# (benchmarks/inpaint_vote_sound.py, docs/inpainting.md): assembled from cached fills, 9
# of 62 cases more than 0.2 dB below the best candidate, against 12 with the wide ring
# alone and 10 with RING alone; run as it is, 11 either way, the shortfalls summing to
# 5.7 dB against 7.8, and the mean over the classes 32.77 dB against 32.69.
NARROW = True
# SHIFT: a second test besides the ring: the cluster's own shape moved aside, clear of the
# hole, by twice its half-thickness plus GAP px in each of DIRECTIONS (each its own fill),
# hidden and filled: a test of the hole's own thickness (a ring around a 2 px scratch makes a 6 px
# one, where the smooth fills catch up with the spectral one). Both tests' errors count.
# Off: on the calibration half it gained on thin damage and texture but misled the vote on
# periodic patterns (-12 dB in that class) at 1.85x the fills' time; measured again one
# direction per fill (benchmarks/inpaint_vote_sound.py), it misleads the vote where holes
# sit on edges (the copy lands on flat content: edges-0/blobs -7 to -9 dB).
SHIFT = False
GAP = 3
DIRECTIONS = ((1, 0), (0, -1))  # down and left, each its own fill
AGREE = 0.5 / 255  # RMS disagreement (in [0, 1] units) below which no vote is needed
# AGREED: what the clusters that do not vote take (their candidates agree, or no ring was
# left to test on): "cheapest", the first candidate, or "box", the box's vote (the mean over
# the tests of the weights that fit every voting ring of the box; the cheapest where
# nothing votes). Every candidate has filled the hole already, so the choice costs
# nothing, and AGREE is an absolute bound (half an 8-bit step: 128 levels of 16-bit data)
# under which the cheapest fill can still cost dB where the fills are good: on the
# calibration half "box" takes edges-0/blobs (53 dB) from -0.27 to within 0.2 dB of its
# best candidate, 14 -> 13 cases below the bound with PRIOR 300.
AGREED = "box"
# POWER: how a ring's errors become weights. 0: the least-squares blend (before stop 49),
# which trusts the ring as if it were the hole: it fits the ring's noise and, where the
# candidates are close on the ring, puts all the weight where the ring's draw happened to
# lean. > 0: the soft vote, each candidate weighted by (e_min / e_k) ** POWER, its ring's
# likelihood under Gaussian errors of 2 POWER independent values (the ring's values are
# far from independent: neighbours share their errors). A clear winner still takes nearly
# all the weight (an error twice the best's gets 2 ** -8 of it), near-ties are hedged.
# Chosen on the calibration half with PRIOR (docs/inpainting.md, "A soft vote").
POWER = 8.0


# Candidates' options the vote sets unless given: Navier-Stokes keeps its own stop (no
# held-out ring of its own, holdout.py), as the vote was measured: the vote already tests
# each candidate on hidden rings, and a second ring inside would double its cost.
OWN_STOP = {"navier-stokes": {"holdout": 0}}


def _solver(name):
    """solve(data, omega, runtime, dtype=, seed=) of a candidate; None if not installed."""
    if name == "biharmonic":
        return poisson.solve
    if name not in available():
        return None
    return load(name).solve


def candidates(names=None) -> list:
    """The installed candidates among `names` (default CANDIDATES), in order."""
    return [n for n in (CANDIDATES if names is None else names) if _solver(n) is not None]


def margin(names=None, ring: int | None = None, crop=None, options=()) -> int:
    """Known pixels the vote reads around a hole: the widest candidate's margin (with its
    options among `options`, else its defaults) plus the widest ring (with SHIFT, the
    farthest shifted copy of the holes of `crop`, a mask)."""
    given = _by_method(options)
    ring = (RING_MAX if SCALE > 0 else RING) if ring is None else ring
    if SHIFT and crop is not None and np.any(crop):
        deepest = float(ndimage.distance_transform_edt(np.pad(crop, 1)).max())
        ring = max(ring, int(np.ceil(2 * deepest)) + GAP + 1)
    reach = 2
    for name in candidates(names):
        if name in available():
            method = get(name)
            own = given.get(name) or method.options()
            reach = max(reach, method.reach(None, own) or 0)
    return reach + ring


def _by_method(options) -> dict:
    """{method name: its options object} of a sequence of candidates' options."""
    return {method_of(type(o)): o for o in options}


def _fill(name, data, omega, runtime, dtype, seed, params):
    given = {**OWN_STOP.get(name, {}), **params.get(name, {})}
    solved = _solver(name)(data, omega, runtime, dtype=dtype, seed=seed, **given)
    return np.asarray(solved, np.float64)


def _groups(labels, count):
    """[indices of `labels` equal to each label 0..count], by one sort."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(count + 2))
    return [order[bounds[k] : bounds[k + 1]] for k in range(count + 1)]


def _weights(fills, truth):
    """Non-negative weights summing to one that minimise |sum_k w_k fills_k - truth|^2
    (fills: (k, n), truth: (n,))."""
    k = fills.shape[0]
    if k == 1:
        return np.ones(1)
    # eliminate the sum constraint: w_last = 1 - sum(others); bounded least squares
    a = (fills[:-1] - fills[-1]).T
    b = truth - fills[-1]
    res = optimize.lsq_linear(a, b, bounds=(0, 1))
    w = np.append(res.x, 1 - res.x.sum())
    if w[-1] < 0:  # the bounds allow sum(others) > 1: renormalise the rare overshoot
        w = np.clip(w, 0, None)
        w /= w.sum()
    return w


def _shifted(omega, dist, members, radius, vote, direction):
    """The test pixels of each voting cluster (module docstring, SHIFT) moved one way, as a
    label image: the cluster's hole pixels moved by d = ceil(2 radius) + GAP along
    `direction` ((dy, dx), unit steps), where they land on known pixels at least 2 px from
    the hole, not taken by another cluster's copy."""
    ny, nx = omega.shape
    ys, xs = np.nonzero(omega)  # members[lab] index these (the hole in C order)
    owner = np.zeros(omega.shape, np.int64)
    free = ~omega & (dist >= 2)
    dy, dx = direction
    for lab in np.flatnonzero(vote):
        sel = members[lab]
        d = int(np.ceil(2 * radius[lab - 1])) + GAP
        y, x = ys[sel] + dy * d, xs[sel] + dx * d
        keep = (y >= 0) & (y < ny) & (x >= 0) & (x < nx)
        y, x = y[keep], x[keep]
        ok = free[y, x] & (owner[y, x] == 0)
        owner[y[ok], x[ok]] = lab
    return owner


def _soft(f, t, power):
    """Each candidate's weight (e_min / e_k) ** power, normalised (e_k: its mean squared
    error on the test values t): the ring's likelihood of each candidate under Gaussian
    errors with `2 * power` independent values, as a Bayesian average of the candidates
    (module docstring, POWER)."""
    e = np.maximum(((f - t) ** 2).mean(axis=1), 1e-20)  # an exact one takes all the weight
    w = (e.min() / e) ** power
    return w / w.sum()


def _fit(f, t, blend, power=0.0):
    """The weights of the candidates' ring fills f ((k, n)) that fit the truth t ((n,)):
    the soft vote (power > 0), the least-squares blend, or the single best candidate."""
    if blend and power > 0:
        return _soft(f, t, power)
    if blend:
        return _weights(f, t)
    w = np.zeros(f.shape[0])
    w[int(np.argmin(((f - t) ** 2).mean(axis=1)))] = 1.0
    return w


def _ring_tests(owners, names, data, omega, runtime, dtype, seed, params):
    """Each candidate's fill of the test pixels (every owner map's pixels hidden beside the
    hole), the true values there and their clusters: (k, c, m), (c, m), (m,); None, None
    and an empty owner list where nothing could be tested."""
    known = ~omega
    parts = []
    for own in owners:
        test_mask = own > 0
        if not test_mask.any() or not (known & ~test_mask).any():
            continue  # nothing to test on, or nothing left to fill from
        hidden = omega | test_mask
        fills_t = [_fill(n, data, hidden, runtime, dtype, seed, params) for n in names]
        parts.append(
            (np.stack([f[:, test_mask] for f in fills_t]), data[:, test_mask], own[test_mask])
        )
    if not parts:
        return None, None, np.zeros(0, int)
    return (
        np.concatenate([p[0] for p in parts], axis=2),
        np.concatenate([p[1] for p in parts], axis=1),
        np.concatenate([p[2] for p in parts]),
    )


def _settled(names, stack, members, radius, thin, count):
    """The clusters decided without a vote (thin ones, and those whose candidates agree),
    and which clusters vote: (choices, one per cluster or None), (vote, by label)."""
    choices = [None] * count
    vote = np.zeros(count + 1, bool)
    for lab in range(1, count + 1):
        sel = members[lab]
        if not sel.size:
            continue
        values = stack[:, :, sel]
        spread = np.sqrt(((values - values.mean(axis=0)) ** 2).mean(axis=(1, 2))).max()
        if thin > 0 and radius[lab - 1] < thin:
            choices[lab - 1] = {
                "pixels": int(sel.size),
                "why": "thin",
                "chosen": names[-1],
                "weights": {names[-1]: 1.0},
            }
        elif len(names) == 1 or spread < AGREE:
            choices[lab - 1] = {
                "pixels": int(sel.size),
                "why": "candidates agree",
                "chosen": names[0],
                "weights": {names[0]: 1.0},
                "spread": float(spread),
            }
        else:
            vote[lab] = True
    return choices, vote


def _votes(tests, vote, count, names, blend, prior, power=0.0):
    """One test's vote (_ring_tests' result): ({cluster: (weights, squared errors (k, m)
    of each candidate on its test values)}, the box's weights or None): each voting
    cluster's fit on its own test pixels, pulled towards the box's fit over every
    cluster's by `prior` (module docstring)."""
    tests, truth, test_owner = tests
    if tests is None:
        return {}, None
    ring_members = _groups(test_owner, count)
    # the box's weights: every voting ring at once
    pooled = _fit(tests.reshape(len(names), -1), truth.reshape(-1), blend, power)
    out = {}
    for lab in np.flatnonzero(vote):
        sel = ring_members[lab]
        if not sel.size:
            continue
        f = tests[:, :, sel].reshape(len(names), -1)
        t = truth[:, sel].reshape(-1)
        w = _fit(f, t, blend, power)
        if prior > 0:  # a small ring's own fit leans on the box's
            w = pooled if np.isinf(prior) else (t.size * w + prior * pooled) / (t.size + prior)
        out[lab] = (w, (f - t) ** 2)
    return out, pooled


def _assemble(names, choices, count, hole_label, stack):
    """The hole's values (c, n): each cluster's pixels mixed from the candidates' fills
    `stack` (k, c, n) by its choice's weights."""
    weights = np.zeros((len(names), count + 1))
    for lab, ch in enumerate(choices, start=1):
        if ch is not None:
            for n, w in ch["weights"].items():
                weights[names.index(n), lab] = w
    return np.einsum("kn,kcn->cn", weights[:, hole_label], stack)


def _choice(names, pixels, why, w, se=None):
    """One cluster's entry of the report: its weights (k,), and its candidates' RMS errors
    on its first test where it had one."""
    out = {
        "pixels": pixels,
        "why": why,
        "chosen": names[int(np.argmax(w))],
        "weights": {n: float(x) for n, x in zip(names, w, strict=True) if x > 0},
    }
    if se is not None:
        out["ring_rmse"] = {
            n: float(x) for n, x in zip(names, np.sqrt(se.mean(axis=1)), strict=True)
        }
    return out


def _decide(names, votes, vote, members, choices, agreed):
    """Each voting cluster's choice from the tests' votes (_votes' results): the mean of
    its votes' weights; and, with `agreed` "box", the clusters that did not vote (their
    candidates agree, or no ring was left to test on) take the mean over the tests of the
    box's weights (AGREED)."""
    for lab in np.flatnonzero(vote):
        cast = [v[lab] for v, _ in votes if lab in v]
        pixels = int(members[lab].size)
        if cast:
            w = np.mean([c[0] for c in cast], axis=0)
            choices[lab - 1] = _choice(names, pixels, "ring vote", w, cast[0][1])
        else:
            choices[lab - 1] = _choice(names, pixels, "no ring to test on", np.eye(len(names))[0])
    boxes = [b for v, b in votes if v and b is not None]
    if agreed == "box" and boxes:
        w = np.mean(boxes, axis=0)
        for lab, ch in enumerate(choices, start=1):
            if ch is not None and ch["why"] in ("candidates agree", "no ring to test on"):
                choices[lab - 1] = {**ch, **_choice(names, ch["pixels"], ch["why"], w)}


def choose(
    data,
    omega,
    runtime,
    *,
    names=None,
    ring: int | None = None,
    blend: bool = True,
    prior: float | None = None,
    scale: float | None = None,
    thin: float = 0.0,
    shift: bool | None = None,
    narrow: bool | None = None,
    agreed: str | None = None,
    power: float | None = None,
    dtype=np.float32,
    seed=None,
    params=None,
):
    """Fill omega in data ((channels, rows, cols) in [0, 1]) by the self-validated choice
    among the candidates (module docstring).

    Returns (filled, report): filled has data's shape, equal to data outside omega;
    report is {"candidates": [...], "choices": [{"pixels", "why", "weights", "ring_rmse",
    "chosen"} per cluster], "ring_pixels": int}; with two rings (`narrow`), the weights
    are the mean of their votes', ring_rmse the wide ring's and ring_pixels both rings'.
    """
    params = params or {}
    ring = RING if ring is None else ring
    prior = PRIOR if prior is None else prior
    scale = SCALE if scale is None else scale
    shift = SHIFT if shift is None else shift
    narrow = NARROW if narrow is None else narrow
    agreed = AGREED if agreed is None else agreed
    power = POWER if power is None else power
    omega = np.asarray(omega, bool)
    names = candidates(names)
    fills = {n: _fill(n, data, omega, runtime, dtype, seed, params) for n in names}
    known = ~omega
    dist = ndimage.distance_transform_edt(known)  # 0 in the hole
    near = dist <= ring
    clusters, count = ndimage.label(near, np.ones((3, 3), bool))
    out = np.array(data, np.float64, copy=True)
    stack = np.stack([fills[n][:, omega] for n in names])  # (k, c, n): the hole's fills
    hole_label = clusters[omega]
    members = _groups(hole_label, count)
    depth = ndimage.distance_transform_edt(omega)  # each hole pixel's half-thickness
    radius = np.asarray(ndimage.maximum(depth, clusters, np.arange(1, count + 1))).reshape(-1)
    choices, vote = _settled(names, stack, members, radius, thin, count)
    ring_pixels = 0
    if vote.any():
        # each known pixel belongs to the ring of its nearest hole pixel's cluster
        _, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
        nearest = clusters[iy, ix]
        # the rings' widths: SCALE x the half-thickness, and (NARROW) RING px for every
        # cluster; each is its own test, and the cluster's weights the mean of their votes
        widths = []
        if scale > 0:
            widths.append(np.clip(np.ceil(scale * radius), ring, RING_MAX))
        if scale <= 0 or (narrow and np.any(widths[0] > ring)):
            widths.append(np.full(count, float(ring)))
        votes = []
        for k, width in enumerate(widths):
            owner = nearest * (known & (dist <= np.append(0, width)[nearest]) & vote[nearest])
            owners = [owner]
            if shift and k == 0:  # and more tests: the clusters' shapes moved aside
                owners += [_shifted(omega, dist, members, radius, vote, d) for d in DIRECTIONS]
            tests = _ring_tests(owners, names, data, omega, runtime, dtype, seed, params)
            ring_pixels += int(tests[2].size)
            votes.append(_votes(tests, vote, count, names, blend, prior, power))

        _decide(names, votes, vote, members, choices, agreed)
    out[:, omega] = _assemble(names, choices, count, hole_label, stack)
    report = {
        "candidates": names,
        "ring": ring,
        "ring_pixels": ring_pixels,
        "choices": [c for c in choices if c is not None],
    }
    return out, report


# ---------------------------------------------------------------------------------------
# method="auto" (clpde.inpainting.registry)


@dataclass(frozen=True)
class AutoOptions:
    """method="auto"'s options: the vote's (choose's docstring), checked on construction.

    Parameters
    ----------
    names : tuple of str, optional
        The candidates, cheapest first (None: CANDIDATES).
    ring : int, optional
        The narrowest ring of known pixels hidden to score them (None: RING).
    blend : bool
        Fill each cluster with the best blend of the candidates (False: the best one).
    prior : float, optional
        The box's weight in each cluster's fit (None: PRIOR).
    scale : float, optional
        A cluster's ring width per pixel of its half-thickness (None: SCALE).
    thin : float
        Clusters at most this thick take the cheapest candidate without a vote.
    shift : bool, optional
        Also test on the cluster's shape moved aside (None: SHIFT).
    narrow : bool, optional
        Also vote on a ring of `ring` px around every cluster, and average the two votes'
        weights (None: NARROW).
    agreed : str, optional
        What the clusters whose candidates agree take: "cheapest" (the first candidate) or
        "box" (the box's vote: the weights that fit every voting ring; None: AGREED).
    power : float, optional
        The soft vote's power (0: the least-squares blend; None: POWER).
    candidate_options : tuple
        Candidates' own options objects (such as CoherenceOptions(epsilon=4)), each for the
        candidate whose class it is; the others keep their defaults.
    """

    names: tuple | None = None
    ring: int | None = None
    blend: bool = True
    prior: float | None = None
    scale: float | None = None
    thin: float = 0.0
    shift: bool | None = None
    narrow: bool | None = None
    agreed: str | None = None
    power: float | None = None
    candidate_options: tuple = ()

    def __post_init__(self) -> None:
        known = ("biharmonic", *METHODS)
        if self.names is not None and (
            isinstance(self.names, str) or any(n not in known for n in self.names)
        ):
            raise InputError(
                f"names must be a tuple of candidates among {', '.join(known)}, not {self.names!r}"
            )
        ring = self.ring
        if ring is not None and (
            isinstance(ring, bool) or not isinstance(ring, (int, np.integer)) or ring < 1
        ):
            raise InputError(f"ring must be an integer >= 1 or None, not {self.ring!r}")
        if self.agreed not in (None, "cheapest", "box"):
            raise InputError(f'agreed must be "cheapest", "box" or None, not {self.agreed!r}')
        for name in ("prior", "scale", "thin", "power"):
            value = getattr(self, name)
            if value is not None and not value >= 0:  # NaN too; inf is allowed
                raise InputError(f"{name} must be a number >= 0, not {value!r}")
        names = CANDIDATES if self.names is None else self.names
        for o in self.candidate_options:
            owner = method_of(type(o))
            if owner not in names:
                raise InputError(
                    f"candidate_options holds {type(o).__name__}, not a candidate's "
                    f"options; give options of {', '.join(n for n in names if n in METHODS)}"
                )


class VoteRun:
    """method="auto" on one box, as one step: `states(every)` runs the vote, after which
    `solution`, `report` (choose's) and the counters are set. A soft mask is applied after
    the vote, as m * filled + (1 - m) * observed."""

    steps, converged, levels, steps_per_level, band_pixels = 0, True, 1, [], 0

    def __init__(self, data, omega, runtime, options, dtype, seed, damage):
        self.data, self.omega, self.runtime, self.options = data, omega, runtime, options
        self.dtype, self.seed, self.damage = dtype, seed, damage
        self.solution = self.report = None

    def states(self, every=None):
        o = self.options
        params = {name: keywords(own) for name, own in _by_method(o.candidate_options).items()}
        solved, self.report = choose(
            self.data,
            self.omega,
            self.runtime,
            names=o.names,
            ring=o.ring,
            blend=o.blend,
            prior=o.prior,
            scale=o.scale,
            thin=o.thin,
            shift=o.shift,
            narrow=o.narrow,
            agreed=o.agreed,
            power=o.power,
            dtype=self.dtype,
            seed=self.seed,
            params=params,
        )
        if self.damage is not None:
            solved = np.where(
                self.omega, self.damage * solved + (1 - self.damage) * self.data, self.data
            )
        self.solution = solved
        return iter(())


def _vote_run(data, omega, runtime, options, *, dtype, progress, seed, fidelity, damage):
    return VoteRun(data, omega, runtime, options, dtype, seed, damage)


@register(
    "auto",
    AutoOptions,
    margin=lambda omega, o: margin(o.names, crop=omega, options=o.candidate_options),
    soft_mask=True,  # VoteRun blends a soft mask itself
    states=_vote_run,
    description="the self-validated choice among the candidates, per cluster of damage",
)
def solve(data, omega, runtime, *, dtype=np.float32, progress=None, seed=None, **options):
    """The vote's fill of one box (registry.py's protocol); `options` are AutoOptions'."""
    run = VoteRun(data, omega, runtime, AutoOptions(**options), dtype, seed, None)
    run.states()
    return run.solution
