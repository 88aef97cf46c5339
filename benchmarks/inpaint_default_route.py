"""A default that picks per cluster of damage by cheap evidence at the hole: would it gain?
From the fills cached by benchmarks/inpaint_vote_cache.py (no filling here), each cluster's
measures of its surround and each candidate's squared error there; a rule then picks, per
cluster, spectral (the default), a smooth fill (biharmonic) or the exemplar, and the case
is scored as if the picked fills had been run.

    python benchmarks/inpaint_vote_cache.py --half both --masks hole   # first: the fills
    python benchmarks/inpaint_default_route.py [--half calibration|test|both]

Measures per cluster (a component of the hole grown by 1 px; clpde/inpainting/choose.py's
detail image: grey minus its local mean over the known pixels):

- radius: its half-thickness (px);
- texture: RMS of the detail on the known pixels within 8 px of it;
- periodicity: the largest autocorrelation of the detail (choose.LAGS) in a window of the
  cluster's bounding box grown by WINDOW px (only for clusters at least 3 px thick);
- repeat: the same autocorrelation's value along two directions (choose.repeat: a straight
  edge repeats along itself only), in the same window;
- gap and separation: how clearly the cluster's border splits into two sides of distinct
  colour (pick.edge_contrast).

Rules (route): periodic clusters to the exemplar (by periodicity or repeat), smooth ones
to biharmonic, edge clusters (gap and separation over thresholds) to a named candidate.
`--clusters` also lists every cluster at least 3 px thick with its measures and each
candidate's PSNR there.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from inpaint_vote_sound import load  # noqa: E402

from tests.cases import inpaint_corpus as corpus  # noqa: E402

WINDOW = 24


def measures(c):
    """Per cluster (label 1..count): {radius, texture, periodicity, repeat, gap,
    separation} (arrays)."""
    from clpde.inpainting import choose, pick

    known = ~c.omega
    detail, ok = choose._detail(c.data, known)
    ring = known & (c.dist <= 8)
    lab = np.arange(1, c.count + 1)
    sq = ndimage.mean(detail.astype(float) ** 2, np.where(ring, c.owner, 0), lab)
    texture = np.sqrt(np.nan_to_num(np.asarray(sq, float)))
    period, repeat = np.zeros(c.count), np.zeros(c.count)
    slices = ndimage.find_objects(c.clusters)
    for k, s in enumerate(slices):
        if s is None or c.radius[k] < 3:
            continue
        y0, y1 = max(s[0].start - WINDOW, 0), s[0].stop + WINDOW
        x0, x1 = max(s[1].start - WINDOW, 0), s[1].stop + WINDOW
        period[k] = choose._periodicity(detail[y0:y1, x0:x1], ok[y0:y1, x0:x1])
        repeat[k] = choose.repeat(detail[y0:y1, x0:x1], ok[y0:y1, x0:x1])
    gap, separation = pick.edge_contrast(c.data, c.omega)
    return {
        "radius": np.asarray(c.radius, float),
        "texture": texture,
        "periodicity": period,
        "repeat": repeat,
        "gap": gap,
        "separation": separation,
    }


def outputs(c):
    """{candidate: the case's output image} (bounds applied, as clpde.inpaint writes)."""
    out = {}
    for k, n in enumerate(c.names):
        filled = c.data.copy()
        filled[:, c.omega] = c.hole[k]
        img = c.case.damaged().copy()
        c.job._write(img, c.box, filled, c.omega)
        out[n] = img
    return out


def route(m, rule):
    """The candidate's name per cluster (spectral unless a rule says otherwise)."""
    pick = np.full(m["radius"].shape, "spectral", object)
    if rule.get("smooth") is not None:
        pick[m["texture"] < rule["smooth"]] = "biharmonic"
    if rule.get("edge") is not None:
        gap, sep, name = rule["edge"]
        pick[(m["gap"] >= gap) & (m["separation"] >= sep) & (m["radius"] >= 3)] = name
    if rule.get("oracle") is not None:  # the better of spectral and `oracle` by the truth
        best = m["truth_" + rule["oracle"]] > m["truth_spectral"]
        pick[best & (m["radius"] >= 3)] = rule["oracle"]
    if rule.get("ring") is not None:  # `name` where its ring error is below spectral's
        w, name, ratio, min_radius = rule["ring"]
        key = f"ring{w}_{name}"
        if key in m:
            better = m[key] < ratio * m[f"ring{w}_spectral"]
            if rule.get("edge_only"):
                better &= (m["gap"] >= rule["edge_only"][0]) & (
                    m["separation"] >= rule["edge_only"][1]
                )
            if rule.get("not_edge"):
                better &= (m["gap"] < rule["not_edge"][0]) | (m["separation"] < rule["not_edge"][1])
            pick[better & (m["radius"] >= min_radius)] = name
    if rule.get("fit") is not None:  # biharmonic where it fits its ring almost exactly
        w, q = rule["fit"]
        if f"ring{w}_var" in m:
            smooth = m[f"ring{w}_biharmonic"] < q * m[f"ring{w}_var"]
            pick[smooth & (m["radius"] >= 3)] = "biharmonic"
    if rule.get("period") is not None:
        measure = m[rule.get("measure", "periodicity")]
        pick[(measure >= rule["period"]) & (m["radius"] >= rule.get("min_radius", 3))] = "exemplar"
    return pick


def ring_errors(c, path):
    """{f"ring{w}_{name}": each cluster's mean squared error on its ring of w px} from a
    cache of ring fills (benchmarks/inpaint_vote_cache.py's file for this case), for the
    candidates stored there."""
    if not path.exists():
        return {}
    z = np.load(path)
    out = {}
    for w in (1, 2, 4, 8):
        if f"mask_ring{w}" not in z.files:
            continue
        hidden = z[f"mask_ring{w}"]
        index = np.full(hidden.shape, -1)
        index[hidden] = np.arange(int(hidden.sum()))
        sel = ~c.omega & (c.dist <= w)
        owner = c.owner[sel]
        count = np.maximum(np.bincount(owner, minlength=c.count + 1)[1:], 1)
        t = c.data[:, sel]
        mean = np.stack([np.bincount(owner, ch, minlength=c.count + 1)[1:] / count for ch in t])
        sq = ((t - mean[:, np.maximum(owner - 1, 0)]) ** 2).sum(axis=0)
        out[f"ring{w}_var"] = np.bincount(owner, sq, minlength=c.count + 1)[1:] / count / len(t)
        for key in z.files:
            if key.startswith(f"fill_ring{w}_"):
                name = key[len(f"fill_ring{w}_") :]
                sq = ((z[key][:, index[sel]] - c.data[:, sel]) ** 2).sum(axis=0)
                err = np.bincount(owner, sq, minlength=c.count + 1)[1:]
                out[f"ring{w}_{name}"] = err / count / c.data.shape[0]
    return out


def cluster_psnr(c, outs, lab, name):
    """PSNR of candidate `name` over cluster `lab`'s hole pixels."""
    sel = c.omega & (c.clusters == lab)
    d = outs[name][sel].astype(float) - c.case.truth[sel].astype(float)
    return 10 * np.log10(c.case.peak**2 / max(np.mean(d**2), 1e-12))


def rules():
    out = {"spectral (today)": {}}
    for p in (0.85, 0.9):
        out[f"period >= {p}"] = {"period": p}
        out[f"repeat >= {p}"] = {"period": p, "measure": "repeat"}
    for w in (1, 2, 4, 8):
        for ratio in (1.0, 0.8, 0.5):
            for r in (3, 5):
                out[f"repeat .85, ring {w} < {ratio} x spectral, r >= {r}"] = {
                    "period": 0.85,
                    "measure": "repeat",
                    "ring": (w, "biharmonic", ratio, r),
                }
    for w in (2, 4):
        for gap, sep in ((0.1, 2.5), (0.1, 3.0), (0.2, 3.0)):
            for ratio in (1.0, 0.8):
                for how in ("edge_only", "not_edge"):
                    out[f"repeat .85, ring {w} < {ratio}, {how} {gap} {sep}"] = {
                        "period": 0.85,
                        "measure": "repeat",
                        "ring": (w, "biharmonic", ratio, 3),
                        how: (gap, sep),
                    }
    for w in (1, 2, 4, 8):
        for q in (0.001, 0.003, 0.01, 0.03):
            out[f"repeat .85, biharmonic fits ring {w} to {q}"] = {
                "period": 0.85,
                "measure": "repeat",
                "fit": (w, q),
            }
    for t in (0.002, 0.004, 0.008, 0.016):
        out[f"repeat .85, texture < {t}"] = {"period": 0.85, "measure": "repeat", "smooth": t}
    for name in ("biharmonic", "coherence", "navier-stokes"):
        for gap in (0.05, 0.1, 0.2):
            for sep in (2.5, 3.0, 4.0):
                out[f"repeat .85, edge {gap} {sep} {name}"] = {
                    "period": 0.85,
                    "measure": "repeat",
                    "edge": (gap, sep, name),
                }
    for name in ("biharmonic", "coherence", "navier-stokes", "exemplar"):
        out[f"repeat .85, oracle {name}"] = {"period": 0.85, "measure": "repeat", "oracle": name}
    return out


def main(argv=None):
    from clpde.inpainting import auto

    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--half", default="calibration")
    parser.add_argument("--clusters", action="store_true")
    parser.add_argument("--rings", default=None, help="a folder of ring fills (ring rules)")
    parser.add_argument("--classes", default=None, help="comma-separated classes only")
    args = parser.parse_args(argv)
    names = auto.candidates()
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    rows = []
    for c in load(halves, names):
        if args.classes and c.case.damage not in args.classes.split(","):
            continue
        m = measures(c)
        if args.rings:
            m.update(ring_errors(c, Path(args.rings) / f"{c.case.name.replace('/', '_')}.npz"))
        outs = outputs(c)
        for n in names:  # each candidate's PSNR per cluster, for the oracle rules
            m["truth_" + n] = np.array([cluster_psnr(c, outs, k + 1, n) for k in range(c.count)])
        rows.append((c, m, outs))
        if args.clusters:
            for k in np.flatnonzero(m["radius"] >= 3):
                ps = " ".join(f"{n[:5]}={cluster_psnr(c, outs, k + 1, n):5.1f}" for n in names)
                print(
                    f"{c.case.name:28s} {k + 1:3d} r={m['radius'][k]:4.1f} "
                    f"per={m['periodicity'][k]:.2f} rep={m['repeat'][k]:.2f} "
                    f"gap={m['gap'][k]:.3f} sep={m['separation'][k]:4.1f}  {ps}"
                )
    for half in halves:
        sel = [r for r in rows if r[0].case.half == half]
        print(f"\n{half} ({len(sel)} cases): rule | mean over classes | per class")
        for label, rule in rules().items():
            by = {}
            for c, m, outs in sel:
                pick = route(m, rule)
                img = outs["spectral"].copy()
                lab = np.zeros(c.omega.shape, int)
                lab[c.omega] = c.hole_label
                for n in set(pick):
                    chosen = np.isin(lab, 1 + np.flatnonzero(pick == n)) & c.omega
                    img[chosen] = outs[n][chosen]
                by.setdefault(c.case.damage, []).append(corpus.psnr(c.case, img))
            means = {d: np.mean(v) for d, v in by.items()}
            print(
                f"{label:44s} {np.mean(list(means.values())):6.2f}  "
                + " ".join(f"{d[:5]}={means[d]:.2f}" for d in corpus.CLASSES if d in means)
            )


if __name__ == "__main__":
    main()
