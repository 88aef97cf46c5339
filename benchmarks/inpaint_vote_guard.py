"""A guarded vote for `method="auto"`: each cluster's own ring vote only where its evidence
is clearly separated, the box's choice elsewhere. Rules assembled from the fills cached by
benchmarks/inpaint_vote_cache.py (no filling here), scored case by case against the best
single candidate, as benchmarks/inpaint_vote_sound.py scores its rules.

    python benchmarks/inpaint_vote_cache.py --half both --masks hole,ring1,ring2,ring4,ring8
    python benchmarks/inpaint_vote_guard.py [--half calibration|test|both] [--cases]

Each case's clusters that vote (their candidates disagree) are scored on two hidden rings:
1 px, and half the cluster's thickness (rounded up to a cached width, 1-8 px). A rule is:

- "now": auto's vote before the guard (each ring's blend pulled to the box's by PRIOR, the
  mean of the two rings' weights);
- "box single": one candidate for every voting cluster of the box, the one whose ring
  error over every voting ring of the box, relative to the best candidate's and averaged
  over the two rings, is least;
- "guard z": a cluster keeps "now" only where its own best candidate on each ring beats
  the box's single candidate there by z standard errors of the paired difference of their
  squared errors (the ring's values); elsewhere it takes the box's single candidate.

Printed per rule and half: the mean PSNR over the classes, the worst margin to the best
candidate, the cases more than 0.2 dB below it and their shortfalls summed.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from inpaint_vote_sound import AGREE, fit, load  # noqa: E402

from tests.cases import inpaint_corpus as corpus  # noqa: E402


class Votes:
    """One case's voting clusters and their two rings' test values."""

    def __init__(self, c, scale=0.5):
        self.c = c
        k = len(c.names)
        self.base = np.zeros((k, c.count + 1))
        self.vote = np.zeros(c.count + 1, bool)
        self.agree = np.zeros(c.count + 1, bool)
        groups = [np.flatnonzero(c.hole_label == lab) for lab in range(c.count + 1)]
        self.pixels = np.array([g.size for g in groups])
        for lab in range(1, c.count + 1):
            sel = groups[lab]
            if not sel.size:
                continue
            v = c.hole[:, :, sel]
            spread = np.sqrt(((v - v.mean(axis=0)) ** 2).mean(axis=(1, 2))).max()
            if spread < AGREE:
                self.base[0, lab] = 1
                self.agree[lab] = True
            else:
                self.vote[lab] = True
        wide = np.ones(c.count + 1)
        wide[1:] = np.clip(np.ceil(scale * c.radius), 1, 8)
        self.rings = []
        for width in (wide, np.ones(c.count + 1)):
            t = c.tests(width)
            self.rings.append({lab: v for lab, v in t.items() if self.vote[lab]})

    def pooled(self, ring):
        if not ring:
            return None, None
        return (
            np.concatenate([f for f, _ in ring.values()], axis=1),
            np.concatenate([t for _, t in ring.values()]),
        )

    def box_single(self):
        """The index of the box's single candidate: least mean relative pooled ring MSE."""
        rel = []
        for ring in self.rings:
            f, t = self.pooled(ring)
            if f is None:
                continue
            e = ((f - t) ** 2).mean(axis=1)
            rel.append(e / max(e.min(), 1e-20))
        if not rel:
            return 0
        return int(np.argmin(np.mean(rel, axis=0)))

    def box_blend(self, blend=True):
        """The mean over the two rings of the weights fitted to every voting ring at once."""
        fits = [fit(f, t, blend) for f, t in map(self.pooled, self.rings) if f is not None]
        return np.mean(fits, axis=0) if fits else None

    def now(self, prior=300.0, blend=True):
        """{lab: weights} of auto's vote (mean of the two rings' fits)."""
        out = {}
        per = []
        for ring in self.rings:
            f, t = self.pooled(ring)
            pooled = fit(f, t, blend) if f is not None and prior > 0 else None
            votes = {}
            for lab, (fl, tl) in ring.items():
                w = fit(fl, tl, blend)
                if pooled is not None:
                    w = (
                        pooled
                        if np.isinf(prior)
                        else (tl.size * w + prior * pooled) / (tl.size + prior)
                    )
                votes[lab] = w
            per.append(votes)
        for lab in np.flatnonzero(self.vote):
            cast = [v[lab] for v in per if lab in v]
            if cast:
                out[lab] = np.mean(cast, axis=0)
        return out

    def separation(self, lab, b):
        """Per ring: (own best candidate a, z of a's lead over candidate b)."""
        out = []
        for ring in self.rings:
            if lab not in ring:
                continue
            f, t = ring[lab]
            se = (f - t) ** 2
            a = int(np.argmin(se.mean(axis=1)))
            d = se[b] - se[a]
            sd = d.std() / np.sqrt(d.size) if d.size > 1 else 0.0
            z = np.inf if a == b else (d.mean() / sd if sd > 0 else np.inf)
            out.append((a, z))
        return out


def _z(f, t, ref):
    """Per ring test (f (k, n), t (n,)): (the best candidate a, z of its lead over `ref`:
    the mean paired difference of their squared errors over its standard error)."""
    se = (f - t) ** 2
    a = int(np.argmin(se.mean(axis=1)))
    if a == ref:
        return a, np.inf
    d = se[ref] - se[a]
    sd = d.std() / np.sqrt(d.size) if d.size > 1 else 0.0
    return a, (d.mean() / sd if sd > 0 else np.inf)


def weights(v: Votes, rule):
    """The rule's weights (k, count + 1)."""
    w = v.base.copy()
    now = v.now(rule.get("prior", 300.0), rule.get("blend", True))
    kind = rule["kind"]
    spectral = v.c.names.index("spectral")
    b = v.box_single() if rule.get("ref", "box") == "box" else spectral
    box_clear = True
    if kind == "guard" and rule.get("level", "cluster") in ("box", "both"):
        tests = [v.pooled(r) for r in v.rings]
        box_clear = all(_z(f, t, b)[1] >= rule["z"] for f, t in tests if f is not None)
    for lab in np.flatnonzero(v.vote):
        if lab not in now:
            w[0, lab] = 1
            continue
        if kind == "now":
            w[:, lab] = now[lab]
        elif kind == "box single":
            w[b, lab] = 1
        elif kind == "guard":
            clear = box_clear
            if rule.get("level", "cluster") in ("cluster", "both"):
                sep = [_z(*r[lab], b) for r in v.rings if lab in r]
                clear = clear and bool(sep) and all(z >= rule["z"] for _, z in sep)
            if clear:
                w[:, lab] = now[lab]
            else:
                w[b, lab] = 1
    to = rule.get("agree_to", "cheapest")
    if to != "cheapest" and v.agree.any():
        k = len(v.c.names)
        if to == "box blend":
            bw = v.box_blend()
        elif to == "box single":
            bw = np.eye(k)[v.box_single()] if v.vote.any() else None
        else:
            bw = None
        if bw is None:
            bw = np.eye(k)[spectral if rule.get("none_to") == "spectral" else 0]
        w[:, v.agree] = bw[:, None]
    return w


RULES = {
    "now": dict(kind="now"),
    "box single": dict(kind="box single"),
    "spectral": dict(kind="guard", ref="spectral", z=np.inf),
}
for _to in ("box blend", "box single"):
    for _none in ("cheapest", "spectral"):
        RULES[f"now, agree: {_to}, else {_none}"] = dict(kind="now", agree_to=_to, none_to=_none)
for _z_ in (1.0, 2.0, 3.0, 5.0, 8.0):
    for _ref in ("box", "spectral"):
        for _level in ("cluster", "box", "both"):
            RULES[f"guard {_ref} {_level} z {_z_}"] = dict(
                kind="guard", ref=_ref, level=_level, z=_z_
            )


def main(argv=None):
    from clpde.inpainting import auto

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    parser.add_argument("--rules", default=None, help="names of RULES, ';'-separated")
    parser.add_argument("--cases", action="store_true", help="list the cases below -0.2 dB")
    args = parser.parse_args(argv)
    names = auto.candidates()
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    rules = RULES if not args.rules else {k: RULES[k] for k in args.rules.split(";")}
    for half in halves:
        cases = [Votes(c) for c in load((half,), names)]
        print(f"\n{half} ({len(cases)} cases): rule | mean over classes | worst | below | sum")
        best = {}
        for v in cases:
            best.setdefault(v.c.case.damage, []).append(v.c.best)
        print(
            f"{'best candidate (oracle)':28s} {np.mean([np.mean(x) for x in best.values()]):6.2f}"
        )
        for label, rule in rules.items():
            by, margins = {}, []
            for v in cases:
                w = weights(v, rule)
                p = v.c.score(np.einsum("kn,kcn->cn", w[:, v.c.hole_label], v.c.hole))
                by.setdefault(v.c.case.damage, []).append(p)
                margins.append((p - v.c.best, v.c.case.name))
            margins.sort()
            below = [m for m in margins if m[0] < -0.2]
            print(
                f"{label:28s} {np.mean([np.mean(x) for x in by.values()]):6.2f} "
                f"{margins[0][0]:+6.2f} ({margins[0][1]}) {len(below):3d} "
                f"{-sum(m for m, _ in below):6.2f}"
            )
            if args.cases:
                print("    " + "; ".join(f"{n} {m:+.2f}" for m, n in below))
            print("    " + " ".join(f"{d}={np.mean(by[d]):.2f}" for d in corpus.CLASSES if d in by))


if __name__ == "__main__":
    main()
