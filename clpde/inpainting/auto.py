"""Self-validation: what `method="auto"` fills each cluster of damage with, measured there.

Which method fills a hole best depends on the hole and on what surrounds it, and a rule
fitted to named cases learns those cases. Here each box of damage measures it instead:

1. Every candidate method fills the box's hole.
2. The hole's pixels are grouped into clusters: the connected components of the hole grown
   by 1 px (so components 2 px apart share one cluster). Where the candidates' fills of a
   cluster agree (their largest RMS difference from the cluster's mean fill is below AGREE,
   half an 8-bit quantisation step), any of them will do: the cheapest is taken and no vote
   is run there.
3. For the clusters that disagree, DECOYS copies of the cluster's own shape are placed on
   known pixels nearby, clear of the damage, the box's edge and each other
   (clpde/inpainting/decoys.py), and every candidate fills the hole and all decoys at once.
   A decoy has the hole's thickness at every pixel, so a candidate's error there is a
   sample of its error in the hole itself (a ring hidden around the hole is not: a thin
   one rewards fills good next to the border, a wide one penalises the texture methods).
4. Each cluster gets the blend of the candidates' fills whose weights, non-negative and
   summing to one, minimise the squared error on its decoys (the benchmark's metric),
   pulled towards the weights that fit every voting cluster's decoys of the box at once,
   as if those added PRIOR values to the cluster's own (a speck of dust's decoys hold a
   few dozen values, too few for five weights). A blend that gives one candidate at least
   SNAP is that candidate alone: blending an exact fill (a periodic pattern's exemplar)
   with a little of another costs far more than it can gain.

The candidate set, the decoys' count, the prior and SNAP were chosen on the calibration
half of tests/cases/inpaint_corpus.py's corpus (benchmarks/inpaint_vote_sound.py;
docs/inpainting.md has the tables), and nothing else was fitted. `choices` in the returned
report says, per cluster, what was chosen and why, with the candidates' decoy errors.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy import ndimage, optimize

from ..errors import InputError
from . import decoys as decoy_module
from . import poisson
from .registry import METHODS, available, get, keywords, load, method_of, register

# The candidates, cheapest first (the first one fills clusters where all agree), chosen on
# the calibration half (benchmarks/inpaint_validate_calibrate.py --quick, the best mean PSNR
# over the classes; docs/inpainting.md has the tables); DEFAULT keeps a cluster where the
# decoys cannot tell it from the best (the best mean over the classes alone).
CANDIDATES = ("biharmonic", "coherence", "navier-stokes", "exemplar", "spectral")
DEFAULT = "spectral"
# Decoys per cluster (decoys.py).
DECOYS = decoy_module.COUNT
# A cluster's weights are its own decoys' fit pulled towards the box's, as if the box's
# decoys added PRIOR values to the cluster's own.
PRIOR = 1000.0
# A blend giving one candidate at least SNAP of the weight is that candidate alone.
SNAP = 0.8
AGREE = 0.5 / 255  # RMS disagreement (in [0, 1] units) below which no vote is needed


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


def margin(names=None, crop=None, options=()) -> int:
    """Known pixels the vote reads around a hole: the widest candidate's margin (with its
    options among `options`, else its defaults) plus the decoys' reach around the largest
    cluster of `crop` (a mask)."""
    given = _by_method(options)
    size = 1
    if crop is not None and np.any(crop):
        labels, _ = ndimage.label(np.asarray(crop, bool), np.ones((3, 3), bool))
        size = max(max(s.stop - s.start for s in sl) for sl in ndimage.find_objects(labels))
    reach = 2
    for name in candidates(names):
        if name in available():
            method = get(name)
            own = given.get(name) or method.options()
            reach = max(reach, method.reach(None, own) or 0)
    d = decoy_module
    return reach + max(d.WINDOW * size, d.MIN_WINDOW) + size + d.GAP


def _by_method(options) -> dict:
    """{method name: its options object} of a sequence of candidates' options."""
    return {method_of(type(o)): o for o in options}


def _fill(name, data, omega, runtime, dtype, seed, params):
    solved = _solver(name)(data, omega, runtime, dtype=dtype, seed=seed, **params.get(name, {}))
    return np.asarray(solved, np.float64)


def _groups(labels, count):
    """[indices of `labels` equal to each label 0..count], by one sort."""
    order = np.argsort(labels, kind="stable")
    bounds = np.searchsorted(labels[order], np.arange(count + 2))
    return [order[bounds[k] : bounds[k + 1]] for k in range(count + 1)]


def _settled(names, stack, members, thin, radius, count):
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
            why, chosen = "thin", names[-1]
        elif len(names) == 1 or spread < AGREE:
            why, chosen = "candidates agree", names[0]
        else:
            vote[lab] = True
            continue
        choices[lab - 1] = {
            "pixels": int(sel.size),
            "why": why,
            "chosen": chosen,
            "weights": {chosen: 1.0},
        }
    return choices, vote


def _weights(fills, truth):
    """Non-negative weights summing to one that minimise |sum_k w_k fills_k - truth|^2
    (fills: (k, n), truth: (n,)); a candidate whose fills are NaN (it could not fill the
    decoys) gets none."""
    ok = np.isfinite(fills[:, 0]) if fills.shape[1] else np.ones(fills.shape[0], bool)
    if not ok.all():
        w = np.zeros(fills.shape[0])
        w[ok] = _weights(fills[ok], truth)
        return w
    k = fills.shape[0]
    if k == 1:
        return np.ones(1)
    # eliminate the sum constraint: w_last = 1 - sum(others); bounded least squares
    res = optimize.lsq_linear((fills[:-1] - fills[-1]).T, truth - fills[-1], bounds=(0, 1))
    w = np.clip(np.append(res.x, 1 - res.x.sum()), 0, None)  # the bounds allow a sum > 1
    return w / w.sum()


def _decoy_tests(names, data, omega, owner, runtime, dtype, seed, params):
    """Every candidate's fill of the decoys (the hole hidden too, as in its own fill), the
    true values there and each value's cluster: (k, n), (n,), (n,) over pixels and
    channels; NaN for a candidate that cannot fill them (an exemplar left without whole
    patches to copy), which the vote then leaves out."""
    test = owner > 0
    hidden = omega | test
    fills = []
    for n in names:
        try:
            fills.append(_fill(n, data, hidden, runtime, dtype, seed, params)[:, test])
        except InputError:
            fills.append(np.full((data.shape[0], int(test.sum())), np.nan))
    lab = np.broadcast_to(owner[test], (data.shape[0], int(test.sum())))
    return np.stack([f.reshape(-1) for f in fills]), data[:, test].reshape(-1), lab.reshape(-1)


def _vote(names, tests, lab, prior, box, snap):
    """One cluster's weights from the decoys (module docstring, 4): its own decoys' blend
    pulled towards the box's (`box`) by `prior` values; the box's alone where it has no
    decoy; a blend within SNAP of one candidate is that candidate. (weights, why, RMS
    error of each candidate on its decoys or None)."""
    fills, truth, of = tests
    mine = of == lab
    if not mine.any():
        w, why, rmse = box, "the box's decoys", None
    else:
        f, t = fills[:, mine], truth[mine]
        w = _weights(f, t)
        w = box if np.isinf(prior) else (t.size * w + prior * box) / (t.size + prior)
        why, rmse = "decoy vote", np.sqrt(((f - t) ** 2).mean(axis=1))  # NaN: no fill
    if w.max() >= snap:
        w = np.eye(len(names))[int(np.argmax(w))]
    return w, why, rmse


def choose(
    data,
    omega,
    runtime,
    *,
    names=None,
    decoys: int | None = None,
    prior: float | None = None,
    snap: float | None = None,
    thin: float = 0.0,
    dtype=np.float32,
    seed=None,
    params=None,
):
    """Fill omega in data ((channels, rows, cols) in [0, 1]) by the self-validated choice
    among the candidates (module docstring).

    Returns (filled, report): filled has data's shape, equal to data outside omega;
    report is {"candidates": [...], "choices": [{"pixels", "why", "weights", "chosen",
    "decoy_rmse"} per cluster], "decoy_pixels": int}.
    """
    params = params or {}
    decoys = DECOYS if decoys is None else decoys
    prior = PRIOR if prior is None else prior
    snap = SNAP if snap is None else snap
    omega = np.asarray(omega, bool)
    names = candidates(names)
    fills = {n: _fill(n, data, omega, runtime, dtype, seed, params) for n in names}
    known = ~omega
    dist = ndimage.distance_transform_edt(known)  # 0 in the hole
    clusters, count = ndimage.label(dist <= 1, np.ones((3, 3), bool))
    out = np.array(data, np.float64, copy=True)
    stack = np.stack([fills[n][:, omega] for n in names])  # (k, c, n): the hole's fills
    hole_label = clusters[omega]
    members = _groups(hole_label, count)
    depth = ndimage.distance_transform_edt(omega)  # each hole pixel's half-thickness
    radius = np.asarray(ndimage.maximum(depth, clusters, np.arange(1, count + 1))).reshape(-1)
    choices, vote = _settled(names, stack, members, thin, radius, count)
    decoy_pixels = 0
    if vote.any():
        voting = np.flatnonzero(vote)
        order = voting[np.argsort([-members[lab].size for lab in voting], kind="stable")]
        texture = decoy_module.detail(data, omega)
        owner, index = decoy_module.place(omega, clusters, order, decoys, texture)
        decoy_pixels = int((owner > 0).sum())
        tests = None
        if decoy_pixels and (known & (owner == 0)).any():
            tests = _decoy_tests(names, data, omega, owner, runtime, dtype, seed, params)
            box = _weights(tests[0], tests[1])  # every voting cluster's decoys at once
        for lab in voting:
            pixels = int(members[lab].size)
            if tests is None:
                k = names.index(DEFAULT) if DEFAULT in names else len(names) - 1
                w, why, rmse = np.eye(len(names))[k], "no decoy fits", None
            else:
                w, why, rmse = _vote(names, tests, lab, prior, box, snap)
            choices[lab - 1] = {
                "pixels": pixels,
                "why": why,
                "chosen": names[int(np.argmax(w))],
                "weights": {n: float(x) for n, x in zip(names, w, strict=True) if x > 0},
            }
            if rmse is not None:
                choices[lab - 1]["decoy_rmse"] = dict(zip(names, rmse.tolist(), strict=True))
    # assemble: each cluster's hole pixels from its weights
    weights = np.zeros((len(names), count + 1))
    for lab, ch in enumerate(choices, start=1):
        if ch is not None:
            for n, w in ch["weights"].items():
                weights[names.index(n), lab] = w
    per_pixel = weights[:, hole_label]  # (k, n)
    out[:, omega] = np.einsum("kn,kcn->cn", per_pixel, stack)
    report = {
        "candidates": names,
        "decoy_pixels": decoy_pixels,
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
    decoys : int, optional
        Decoys (copies of a cluster's shape on known pixels nearby) per cluster (None:
        DECOYS).
    prior : float, optional
        The box's weight in each cluster's fit, in values (None: PRIOR).
    snap : float, optional
        A blend giving one candidate at least this weight is that candidate alone (None:
        SNAP; above 1: never).
    thin : float
        Clusters at most this thick take the last candidate without a vote.
    candidate_options : tuple
        Candidates' own options objects (such as CoherenceOptions(epsilon=4)), each for the
        candidate whose class it is; the others keep their defaults.
    """

    names: tuple | None = None
    decoys: int | None = None
    prior: float | None = None
    snap: float | None = None
    thin: float = 0.0
    candidate_options: tuple = ()

    def __post_init__(self) -> None:
        known = ("biharmonic", *METHODS)
        if self.names is not None and (
            isinstance(self.names, str) or any(n not in known for n in self.names)
        ):
            raise InputError(
                f"names must be a tuple of candidates among {', '.join(known)}, not {self.names!r}"
            )
        count = self.decoys
        if count is not None and (
            isinstance(count, bool) or not isinstance(count, (int, np.integer)) or count < 1
        ):
            raise InputError(f"decoys must be an integer >= 1 or None, not {self.decoys!r}")
        for name in ("prior", "snap", "thin"):
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
            decoys=o.decoys,
            prior=o.prior,
            snap=o.snap,
            thin=o.thin,
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
