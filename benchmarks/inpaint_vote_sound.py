"""Is `method="auto"`'s vote sound, and which test makes it so? Vote rules assembled from the
fills cached by benchmarks/inpaint_vote_cache.py (no filling here), scored case by case
against the best single candidate.

    python benchmarks/inpaint_vote_cache.py --half both      # first: the fills (long)
    python benchmarks/inpaint_vote_sound.py [--half calibration|test|both] [--cases]
    python benchmarks/inpaint_vote_sound.py --real [--vote rings|decoys] [--only NAMES]
        [--prior P] [--narrow 0|1] [--agreed cheapest|box] [--power P]
    python benchmarks/inpaint_vote_sound.py --time [--half ...]   # auto's time / default's
    python benchmarks/inpaint_vote_sound.py --vote-time [--half ...]  # the vote's own time

--real runs a vote itself (auto.choose's rings, or inpaint_vote_decoys.choose) on the
cached hole fills, its test fills memoised in benchmarks/results/decoy_cache/.

A rule is: which test pixels score each cluster (its ring, as wide as SCALE x its
half-thickness between 1 and 8 px and rounded up to a cached width; and/or its own shape
moved aside, "shift"), blend or pick, and the prior that pulls each cluster's weights
towards the box's (auto.py's PRIOR). Printed per rule and half: the mean PSNR over the
classes, the worst margin to the best candidate, and the cases more than 0.2 dB below it.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from inpaint_vote_cache import CACHE, RINGS, SHIFTS, shifted  # noqa: E402

from tests.cases import inpaint_corpus as corpus  # noqa: E402

AGREE = 0.5 / 255


class Case:
    """One cached case: its fills, clusters and scoring."""

    def __init__(self, case, z, names):
        from clpde import Inpainting

        self.case, self.names = case, names
        self.job = Inpainting(case.damaged(), case.mask, channel_axis=case.channel_axis)
        self.box = (0, case.mask.shape[0], 0, case.mask.shape[1])
        self.data = self.job._box_data(self.box)
        omega = self.omega = case.mask
        known = ~omega
        self.dist, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
        self.clusters, self.count = ndimage.label(self.dist <= 1, np.ones((3, 3), bool))
        self.owner = np.where(known, self.clusters[iy, ix], 0)
        depth = ndimage.distance_transform_edt(omega)
        self.radius = np.asarray(
            ndimage.maximum(depth, self.clusters, np.arange(1, self.count + 1))
        ).reshape(-1)
        self.hole_label = self.clusters[omega]
        self.z = z
        self.hole = np.stack([z[f"fill_hole_{n}"] for n in names]).astype(np.float64)
        self.seconds = {n: float(z[f"sec_hole_{n}"]) for n in names}
        self.single = {n: self.score(self.hole[k]) for k, n in enumerate(names)}
        self.best = max(self.single.values())
        self.shift_owner = {k: shifted(omega, k) for k in SHIFTS if f"mask_shift{k}" in z.files}

    def score(self, values):
        filled = self.data.copy()
        filled[:, self.omega] = values
        out = self.case.damaged().copy()
        self.job._write(out, self.box, filled, self.omega)
        return corpus.psnr(self.case, out)

    def test_values(self, key, pixels):
        """Every candidate's fill (k, c, m) of `pixels` (a mask) from the cached test `key`."""
        hidden = self.z[f"mask_{key}"]
        index = np.full(hidden.shape, -1)
        index[hidden] = np.arange(int(hidden.sum()))
        at = index[pixels]
        return np.stack([self.z[f"fill_{key}_{n}"][:, at] for n in self.names]).astype(float)

    def tests(self, lab_width, use_ring=True, use_shift=False, band=False):
        """{cluster: (fills (k, n), truth (n,))} of the voting clusters' test pixels."""
        out = {}
        groups = {}
        if use_ring:
            for lab in range(1, self.count + 1):
                w = lab_width[lab]
                cached = next(r for r in RINGS if r >= w and f"mask_ring{r}" in self.z.files)
                groups.setdefault(cached, []).append(lab)
        for cached, labs in groups.items():
            width = lab_width[self.owner]
            sel = np.isin(self.owner, labs) & (self.dist <= width) & ~self.omega
            if band:  # only the ring's inner half (the pixels deepest in the grown hole)
                sel &= self.dist <= np.maximum(1, np.ceil(width / 2))
            f = self.test_values(f"ring{cached}", sel)
            t = self.data[:, sel]
            lab_of = self.owner[sel]
            for lab in labs:
                m = lab_of == lab
                out[lab] = [f[:, :, m], t[:, m]]
        if use_shift:
            for k, own in self.shift_owner.items():
                sel = own > 0
                f = self.test_values(f"shift{k}", sel)
                t = self.data[:, sel]
                lab_of = own[sel]
                for lab in np.unique(lab_of):
                    m = lab_of == lab
                    if lab in out:
                        out[lab] = [
                            np.concatenate([out[lab][0], f[:, :, m]], axis=2),
                            np.concatenate([out[lab][1], t[:, m]], axis=1),
                        ]
                    else:
                        out[lab] = [f[:, :, m], t[:, m]]
        return {lab: (f.reshape(len(self.names), -1), t.reshape(-1)) for lab, (f, t) in out.items()}


def fit(f, t, blend):
    from clpde.inpainting import auto

    if blend:
        return auto._weights(f, t)
    w = np.zeros(f.shape[0])
    w[int(np.argmin(((f - t) ** 2).mean(axis=1)))] = 1.0
    return w


def apply(c: Case, rule):
    """The rule's fill of the case's hole: (values (c, n), weights (k, count + 1))."""
    k = len(c.names)
    weights = np.zeros((k, c.count + 1))
    groups = [np.flatnonzero(c.hole_label == lab) for lab in range(c.count + 1)]
    vote = np.zeros(c.count + 1, bool)
    for lab in range(1, c.count + 1):
        sel = groups[lab]
        if not sel.size:
            continue
        v = c.hole[:, :, sel]
        spread = np.sqrt(((v - v.mean(axis=0)) ** 2).mean(axis=(1, 2))).max()
        if spread < AGREE:
            weights[0, lab] = 1
        else:
            vote[lab] = True
    width = np.ones(c.count + 1)
    width[1:] = np.clip(np.ceil(rule.get("scale", 0.5) * c.radius), 1, 8)
    if rule.get("fixed"):
        width[:] = rule["fixed"]
    tests = c.tests(width, rule.get("ring", True), rule.get("shift", False), rule.get("band"))
    if rule.get("also"):  # a second ring, of this fixed width (its own fill), pooled
        more = c.tests(np.full(c.count + 1, float(rule["also"])), True, False)
        for lab, (f, t) in more.items():
            if lab in tests:
                tests[lab] = (
                    np.concatenate([tests[lab][0], f], 1),
                    np.concatenate([tests[lab][1], t]),
                )
            else:
                tests[lab] = (f, t)
    tests = {lab: v for lab, v in tests.items() if vote[lab]}
    pooled = None
    if rule.get("top"):
        return top_average(c, vote, weights, rule)
    if rule.get("mix"):  # the mean of two rules' weights
        wa = apply(c, RULES[rule["mix"][0]])[1]
        wb = apply(c, RULES[rule["mix"][1]])[1]
        weights = 0.5 * (wa + wb)
        return np.einsum("kn,kcn->cn", weights[:, c.hole_label], c.hole), weights
    if rule.get("cv") and tests:
        single = cross_validated(c, width, vote)
        if single is not None:
            for lab in np.flatnonzero(vote):
                weights[:, lab] = 0
                weights[single, lab] = 1
            per = weights[:, c.hole_label]
            return np.einsum("kn,kcn->cn", per, c.hole), weights
    if tests and rule["prior"] > 0:
        pooled = fit(
            np.concatenate([f for f, _ in tests.values()], axis=1),
            np.concatenate([t for _, t in tests.values()]),
            rule["blend"],
        )
    for lab in np.flatnonzero(vote):
        if lab not in tests:
            weights[0, lab] = 1
            continue
        f, t = tests[lab]
        w = fit(f, t, rule["blend"])
        if pooled is not None:
            p = rule["prior"]
            w = pooled if np.isinf(p) else (t.size * w + p * pooled) / (t.size + p)
        weights[:, lab] = w
    per = weights[:, c.hole_label]
    return np.einsum("kn,kcn->cn", per, c.hole), weights


def top_average(c, vote, weights, rule):
    """Each voting cluster: the equal blend of the `top` candidates whose relative errors,
    averaged over the tests (rings of the widths in `rule["widths"]`, 0 for the matched
    width SCALE x half-thickness, and the shift when `rule["shift"]`), are least; each
    test's errors pulled towards the box's by PRIOR as the weights are."""
    scores = []  # per test: {lab: mixed relative errors (k,)}
    parts = []
    for w in rule["widths"]:
        width = np.ones(c.count + 1)
        width[1:] = np.clip(np.ceil(rule.get("scale", 0.5) * c.radius), 1, 8) if w == 0 else w
        parts.append(c.tests(width, True, False))
    if rule.get("shift"):
        parts.append(c.tests(np.ones(c.count + 1), False, True))
    prior = rule["prior"]
    for tests in parts:
        tests = {lab: v for lab, v in tests.items() if vote[lab]}
        if not tests:
            continue
        f, t = _pool(tests, vote)
        pooled = ((f - t) ** 2).mean(axis=1)
        out = {}
        for lab, (fl, tl) in tests.items():
            own = ((fl - tl) ** 2).mean(axis=1)
            e = pooled if np.isinf(prior) else (tl.size * own + prior * pooled) / (tl.size + prior)
            out[lab] = e / e.min()
        scores.append(out)
    for lab in np.flatnonzero(vote):
        rel = [s[lab] for s in scores if lab in s]
        if not rel:
            weights[0, lab] = 1
            continue
        r = np.mean(rel, axis=0)
        pick = np.argsort(r)[: rule["top"]]
        weights[:, lab] = 0
        weights[pick, lab] = 1 / len(pick)
    per = weights[:, c.hole_label]
    return np.einsum("kn,kcn->cn", per, c.hole), weights


def _pool(tests, vote):
    sel = [v for lab, v in tests.items() if vote[lab]]
    if not sel:
        return None, None
    return np.concatenate([f for f, _ in sel], axis=1), np.concatenate([t for _, t in sel])


def cross_validated(c, width, vote):
    """The box's choice by cross-validation between its two tests (ring, shift): each
    single candidate scored on both, each test's blend scored on the other (errors relative
    to the best single candidate's on that test); the index of the single candidate that
    wins, or None where a blend does."""
    from clpde.inpainting import auto

    fr, tr = _pool(c.tests(width, True, False), vote)
    fs, ts = _pool(c.tests(width, False, True), vote)
    if fr is None or fs is None:
        return None
    er = ((fr - tr) ** 2).mean(axis=1)
    es = ((fs - ts) ** 2).mean(axis=1)
    rel = 0.5 * (er / er.min() + es / es.min())
    wr, ws = auto._weights(fr, tr), auto._weights(fs, ts)
    blend_r = ((ws @ fr - tr) ** 2).mean() / er.min()  # fitted on the shift, scored on the ring
    blend_s = ((wr @ fs - ts) ** 2).mean() / es.min()
    blend = 0.5 * (blend_r + blend_s)
    return int(np.argmin(rel)) if rel.min() <= blend else None


RULES = {
    "now: scale .5, blend, prior 300": dict(scale=0.5, blend=True, prior=300.0),
    "scale .5, pick, prior 300": dict(scale=0.5, blend=False, prior=300.0),
    "scale .5, blend, box only": dict(scale=0.5, blend=True, prior=np.inf),
    "scale .5, pick, box only": dict(scale=0.5, blend=False, prior=np.inf),
    "scale .5, blend, own": dict(scale=0.5, blend=True, prior=0.0),
    "scale 1, blend, prior 300": dict(scale=1.0, blend=True, prior=300.0),
    "scale 1, blend, box only": dict(scale=1.0, blend=True, prior=np.inf),
    "scale 1, pick, box only": dict(scale=1.0, blend=False, prior=np.inf),
    "ring 1, blend, prior 300": dict(scale=0.0, blend=True, prior=300.0),
    "ring 4, blend, box only": dict(scale=0.0, fixed=4, blend=True, prior=np.inf),
    "scale 1 inner half, blend, box": dict(scale=1.0, blend=True, prior=np.inf, band=True),
    "shift, blend, prior 300": dict(scale=0.5, ring=False, shift=True, blend=True, prior=300.0),
    "shift, blend, box only": dict(scale=0.5, ring=False, shift=True, blend=True, prior=np.inf),
    "shift, pick, box only": dict(scale=0.5, ring=False, shift=True, blend=False, prior=np.inf),
    "ring .5 + shift, blend, prior 300": dict(scale=0.5, shift=True, blend=True, prior=300.0),
    "ring .5 + shift, blend, box only": dict(scale=0.5, shift=True, blend=True, prior=np.inf),
    "scale 1 + shift, blend, box only": dict(scale=1.0, shift=True, blend=True, prior=np.inf),
    "ring 1, blend, box only": dict(scale=0.0, blend=True, prior=np.inf),
    "ring 1, blend, own": dict(scale=0.0, blend=True, prior=0.0),
    "ring 1, pick, prior 300": dict(scale=0.0, blend=False, prior=300.0),
    "ring 1 + shift, blend, prior 300": dict(scale=0.0, shift=True, blend=True, prior=300.0),
    "ring 1 + shift, blend, box only": dict(scale=0.0, shift=True, blend=True, prior=np.inf),
    "ring 1 + shift, blend, prior 1000": dict(scale=0.0, shift=True, blend=True, prior=1000.0),
    "cv ring 1 / shift, blend prior 300": dict(
        scale=0.0, shift=True, blend=True, prior=300.0, cv=True
    ),
    "cv ring .5 / shift, blend prior 300": dict(
        scale=0.5, shift=True, blend=True, prior=300.0, cv=True
    ),
    "top2 ring1+shift prior 300": dict(top=2, widths=(1,), shift=True, prior=300.0, scale=0),
    "top3 ring1+shift prior 300": dict(top=3, widths=(1,), shift=True, prior=300.0, scale=0),
    "top2 ring1+match+shift prior 300": dict(
        top=2, widths=(1, 0), shift=True, prior=300.0, scale=1.0
    ),
    "top3 ring1+match+shift prior 300": dict(
        top=3, widths=(1, 0), shift=True, prior=300.0, scale=1.0
    ),
    "top2 ring1+ring4+shift prior 300": dict(top=2, widths=(1, 4), shift=True, prior=300.0),
    "top1 ring1+ring4+shift prior 300": dict(top=1, widths=(1, 4), shift=True, prior=300.0),
    "top2 ring1 prior 300": dict(top=2, widths=(1,), prior=300.0, scale=0),
    "ring .5 + ring 1, blend, prior 300": dict(scale=0.5, also=1, blend=True, prior=300.0),
    "mean of now and ring 1": dict(
        mix=("now: scale .5, blend, prior 300", "ring 1, blend, prior 300"), scale=0
    ),
}


def load(halves, names):
    cases = []
    for case in corpus.build():
        if case.half not in halves:
            continue
        path = CACHE / f"{case.name.replace('/', '_')}.npz"
        if path.exists():
            cases.append(Case(case, np.load(path), names))
    return cases


DECOY_CACHE = CACHE.parent / "decoy_cache"


def _hole_first(c, hole, fill):
    """auto._fill for case c: the hole's own fills from the cache (`hole`: {candidate: its
    hole pixels}), any other mask (a hidden ring, a decoy) through `fill`."""

    def cached(name, data, omega, *rest):
        if np.array_equal(omega, c.omega):
            out = c.data.copy()
            out[:, omega] = hole[name]
            return out
        return fill(name, data, omega, *rest)

    return cached


def _cached_fill(original, case_name, seconds):
    """auto._fill memoised on disk by (case, candidate, hidden mask): the decoy fills, so
    that the vote's parameters can be varied without filling again; `seconds` collects
    each fill's time (as measured when it was first made)."""
    import hashlib
    import time

    def fill(name, data, omega, *rest):
        digest = hashlib.sha1(np.packbits(omega).tobytes()).hexdigest()[:16]
        path = DECOY_CACHE / f"{case_name.replace('/', '_')}-{name}-{digest}.npz"
        if path.exists():
            z = np.load(path)
            seconds.append(float(z["sec"]))
            out = np.array(data, np.float64, copy=True)
            out[:, omega] = z["fill"]
            return out
        start = time.perf_counter()
        out = original(name, data, omega, *rest)
        sec = time.perf_counter() - start
        seconds.append(sec)
        DECOY_CACHE.mkdir(parents=True, exist_ok=True)
        tmp = path.with_suffix(".tmp.npz")
        np.savez(tmp, fill=out[:, omega].astype(np.float32), sec=sec)
        tmp.replace(path)
        return out

    return fill


def real(half, cases=None, vote="rings", **options):
    """auto.choose as it is (vote "rings"), or the vote on decoys of the hole's own shape
    (vote "decoys": inpaint_vote_decoys.choose), case by case against the best single
    candidate; the hole's fills from the cache, the others memoised in DECOY_CACHE. Per
    class mean PSNR, the cases more than 0.2 dB below the best candidate, and the vote's
    fill time against the spectral fill's (the hole's fills' cached seconds plus the test
    fills')."""
    import inpaint_vote_decoys

    from clpde.inpainting import auto
    from clpde.runtime import get_runtime

    chooser = inpaint_vote_decoys.choose if vote == "decoys" else auto.choose
    options = {k: v for k, v in options.items() if v is not None}

    runtime = get_runtime()
    names = auto.candidates()
    halves = ("calibration", "test") if half == "both" else (half,)
    original = auto._fill
    for h in halves:
        rows, t_auto, t_spectral = [], 0.0, 0.0
        for c in load((h,), names):
            if cases and not any(p in c.case.name for p in cases):
                continue
            hole = {n: c.hole[k] for k, n in enumerate(names)}
            seconds = []
            auto._fill = _hole_first(c, hole, _cached_fill(original, c.case.name, seconds))
            try:
                filled, report = chooser(c.data, c.omega, runtime, seed=0, **options)
            finally:
                auto._fill = original
            p = c.score(filled[:, c.omega])
            sec = sum(c.seconds.values()) + sum(seconds)
            t_auto += sec
            t_spectral += c.seconds["spectral"]
            why = {}
            for ch in report["choices"]:
                key = f"{ch['why']}:{ch['chosen']}"
                why[key] = why.get(key, 0) + ch["pixels"]
            rows.append((c.case.damage, c.case.name, p, p - c.best))
            print(
                f"{c.case.name} {p:.2f} {p - c.best:+.2f} {sec:.1f} s "
                f"best={max(c.single, key=c.single.get)} "
                + " ".join(f"{k}={v}" for k, v in sorted(why.items(), key=lambda kv: -kv[1])[:3]),
                flush=True,
            )
        by = {}
        for d, _, p, _ in rows:
            by.setdefault(d, []).append(p)
        below = sorted((m, n) for _, n, _, m in rows if m < -0.2)
        print(
            f"\n{h}: vote on {vote} {options}, mean over classes "
            f"{np.mean([np.mean(v) for v in by.values()]):.2f}, {len(below)} of {len(rows)} "
            f"cases more than 0.2 dB below the best candidate (shortfalls sum "
            f"{-sum(m for m, _ in below):.2f} dB): " + "; ".join(f"{n} {m:+.2f}" for m, n in below)
        )
        print(" ".join(f"{d}={np.mean(by[d]):.2f}" for d in corpus.CLASSES if d in by))
        print(f"time: auto {t_auto:.1f} s, spectral {t_spectral:.1f} s, x{t_auto / t_spectral:.2f}")


def vote_seconds(half):
    """The vote's own CPU seconds (auto.choose with every fill read from the caches, so that
    only the weighing is timed), the least-squares blend (power 0, prior 1000) against the
    soft vote (auto's defaults), each run once to read its files first."""
    import time

    from clpde.inpainting import auto
    from clpde.runtime import get_runtime

    runtime, names, original = get_runtime(), auto.candidates(), auto._fill
    total = {"least-squares": 0.0, "soft": 0.0}
    rules = {"least-squares": dict(power=0.0, prior=1000.0), "soft": {}}
    for c in load(("calibration", "test") if half == "both" else (half,), names):
        hole = {n: c.hole[k] for k, n in enumerate(names)}
        auto._fill = _hole_first(c, hole, _cached_fill(original, c.case.name, []))
        try:
            for label, rule in rules.items():
                auto.choose(c.data, c.omega, runtime, seed=0, **rule)
                start = time.process_time()
                auto.choose(c.data, c.omega, runtime, seed=0, **rule)
                total[label] += time.process_time() - start
        finally:
            auto._fill = original
    print(" ".join(f"{k} {v:.2f} s" for k, v in total.items()))


def timed(half):
    """clpde.inpaint's time with method="auto" against the default's, per class: each
    method once on the first case to build its kernels, then one run of each per case."""
    import time

    import clpde

    halves = ("test", "calibration") if half == "both" else (half,)
    warm = False
    for h in halves:
        by = {}
        for case in corpus.build():
            if case.half != h:
                continue
            damaged = case.damaged()
            seconds = []
            for method in (None, "auto"):
                kw = dict(channel_axis=case.channel_axis, method=method, progress=False, seed=0)
                if not warm:
                    clpde.inpaint(damaged, case.mask, **kw)
                start = time.perf_counter()
                clpde.inpaint(damaged, case.mask, **kw)
                seconds.append(time.perf_counter() - start)
            warm = True
            by.setdefault(case.damage, []).append(seconds)
            print(f"{case.name} default {seconds[0]:.2f} s, auto {seconds[1]:.2f} s", flush=True)
        total = np.sum([s for v in by.values() for s in v], axis=0)
        print(f"\n{h}: auto {total[1]:.1f} s, default {total[0]:.1f} s, x{total[1] / total[0]:.2f}")
        print(
            " ".join(
                f"{d}=x{np.sum([s[1] for s in by[d]]) / np.sum([s[0] for s in by[d]]):.1f}"
                for d in corpus.CLASSES
                if d in by
            ),
            flush=True,
        )


def main(argv=None):
    from clpde.inpainting import auto

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    parser.add_argument("--rules", default=None, help="names of RULES, ';'-separated")
    parser.add_argument("--cases", action="store_true", help="list the cases below -0.2 dB")
    parser.add_argument("--real", action="store_true", help="run auto.choose itself (its defaults)")
    parser.add_argument("--time", action="store_true", help="auto's time against the default's")
    parser.add_argument("--vote-time", action="store_true", help="the vote's own CPU time")
    parser.add_argument("--only", default=None, help="--real: case names containing these, ','")
    parser.add_argument("--vote", default="rings", choices=("rings", "decoys"), help="--real")
    parser.add_argument("--prior", type=float, default=None, help="--real: the vote's prior")
    parser.add_argument("--narrow", type=int, default=None, help="--real --vote rings: narrow")
    parser.add_argument("--agreed", default=None, help="--real --vote rings: agreed")
    parser.add_argument("--power", type=float, default=None, help="--real --vote rings: power")
    parser.add_argument("--snap", type=float, default=None, help="--real --vote decoys: snap")
    parser.add_argument("--decoys", type=int, default=None, help="--real --vote decoys: count")
    args = parser.parse_args(argv)
    if args.time:
        return timed(args.half)
    if args.vote_time:
        return vote_seconds(args.half)
    if args.real:
        only = args.only.split(",") if args.only else None
        return real(
            args.half,
            only,
            args.vote,
            prior=args.prior,
            snap=args.snap,
            decoys=args.decoys,
            narrow=None if args.narrow is None else bool(args.narrow),
            agreed=args.agreed,
            power=args.power,
        )
    names = auto.candidates()
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    cases = load(halves, names)
    rules = RULES if not args.rules else {k: RULES[k] for k in args.rules.split(";")}
    for half in halves:
        sel = [c for c in cases if c.case.half == half]
        print(f"\n{half} ({len(sel)} cases): rule | mean over classes | worst | below -0.2 dB")
        best_means = {}
        for c in sel:
            best_means.setdefault(c.case.damage, []).append(c.best)
        print(
            f"{'best candidate (oracle)':36s} "
            f"{np.mean([np.mean(v) for v in best_means.values()]):6.2f}"
        )
        for n in names:
            by = {}
            for c in sel:
                by.setdefault(c.case.damage, []).append(c.single[n])
            below = sum(c.single[n] - c.best < -0.2 for c in sel)
            print(f"{n:36s} {np.mean([np.mean(v) for v in by.values()]):6.2f}  {below:3d}")
        for label, rule in rules.items():
            by, margins = {}, []
            for c in sel:
                values, _ = apply(c, rule)
                p = c.score(values)
                by.setdefault(c.case.damage, []).append(p)
                margins.append((p - c.best, c.case.name, max(c.single, key=c.single.get)))
            margins.sort()
            below = [m for m in margins if m[0] < -0.2]
            print(
                f"{label:36s} {np.mean([np.mean(v) for v in by.values()]):6.2f} "
                f"{margins[0][0]:+6.2f} ({margins[0][1]}) {len(below):3d}"
            )
            if args.cases:
                print("    " + "; ".join(f"{n} {m:+.2f} ({b})" for m, n, b in below))


if __name__ == "__main__":
    main()
