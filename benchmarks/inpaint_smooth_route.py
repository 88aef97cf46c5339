"""Which thick clusters should the default give to the smooth (biharmonic) fill? Measures of
each cluster's surround against what the two fills score there, on the corpus.

    PYTHONPATH=. python benchmarks/inpaint_smooth_route.py cache [--half both]
    PYTHONPATH=. python benchmarks/inpaint_smooth_route.py rules [--half both] [--clusters]

`cache` fills every case of tests/cases/inpaint_corpus.py once (the whole image one box) by
the default as it was before the smooth route (method "pick", route=False) and by the
host's biharmonic fill of every cluster (clpde/inpainting/smooth.py), and by the spectral
fill with a ring of RING px of known pixels hidden around the hole as well (as the opt-in
smooth vote predicts it, pick.RING_SPECTRAL); stored in
benchmarks/results/smooth_route/<case>.npz with each fill's CPU seconds.

`rules` scores routes from that cache: per cluster at least pick.SMOOTH_RADIUS thick that
is not periodic, the biharmonic fill where a rule on the cluster's measures says so, the
default's elsewhere; per class and half the mean PSNR in the hole (bounds applied, as
clpde.inpaint writes). Measures per cluster (window: its bounding box grown by
pick.WINDOW, as the periodicity test's; detail: choose._detail, grey minus its local mean):

- radius: half-thickness (px); texture: RMS of the detail on the known pixels within 8 px;
- rho: the detail's normalised autocorrelation in the window at the lags of chessboard
  length round(radius) (mean over those lags): how far the fine detail stays predictable;
- rough: texture over the standard deviation of the grey known pixels in the window;
- gap, sep: pick.edge_contrast;
- fit: the host biharmonic fill's mean squared error on the cluster's hidden ring
  (smooth.ring_errors) over the ring's detail energy: about 1 where the smooth fill misses
  only the fine detail; fitvar: the same over the ring's variance;
- rough2: texture over the 8 px ring's own standard deviation;
- ratio: the biharmonic ring error over the spectral one (the opt-in smooth vote's test).

Rules also blend the two fills (a fixed weight, or per pixel one minus the detail's
autocorrelation at the pixel's depth). `--not-edge` leaves the clusters on a clear edge
(pick.EDGE_GAP, pick.EDGE_SEPARATION) to the default, as the route does.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from scipy import fft as sfft
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases import inpaint_corpus as corpus  # noqa: E402

RING = 4
CACHE = Path(__file__).resolve().parent / "results" / "smooth_route"
NAMES = ("pick", "biharmonic")


def _path(case):
    return CACHE / f"{case.name.replace('/', '_')}.npz"


def _job(case):
    from clpde import Inpainting

    job = Inpainting(case.damaged(), case.mask, channel_axis=case.channel_axis)
    box = (0, case.mask.shape[0], 0, case.mask.shape[1])
    return job, box, job._box_data(box)


def cache(halves, only=None):
    from clpde.inpainting import pick, smooth
    from clpde.inpainting.registry import keywords, load
    from clpde.inpainting.spectral import SpectralOptions
    from clpde.runtime import get_runtime

    runtime = get_runtime()
    CACHE.mkdir(parents=True, exist_ok=True)
    quick = {**keywords(SpectralOptions()), **pick.RING_SPECTRAL}

    def host(d, o):
        parts = pick.clusters_of(o)
        return smooth.fill(d, o, parts[0], np.arange(1, parts[1] + 1))

    fills = {
        "pick": lambda d, o: load("pick").solve(d, o, runtime, seed=0, route=False),
        "biharmonic": host,
        "spectral": lambda d, o: load("spectral").solve(d, o, runtime, seed=0, **quick),
    }
    cases = [c for c in corpus.build() if c.half in halves]
    if only:
        cases = [c for c in cases if c.name in only.split(",")]
    for i, case in enumerate(cases):
        path = _path(case)
        if path.exists():
            continue
        _, _, data = _job(case)
        omega = case.mask
        known = ~omega
        ring = omega | (known & (ndimage.distance_transform_edt(known) <= RING))
        store = {"mask_ring": ring}
        for key, hidden, names in (
            ("hole", omega, NAMES),
            ("ring", ring, NAMES[1:] + ("spectral",)),
        ):
            for n in names:
                t0 = time.process_time()
                out = np.asarray(fills[n](data, hidden), np.float64)
                store[f"sec_{key}_{n}"] = np.array(time.process_time() - t0)
                store[f"fill_{key}_{n}"] = out[:, hidden].astype(np.float32)
        tmp = path.with_suffix(".tmp.npz")
        np.savez_compressed(tmp, **store)
        tmp.replace(path)
        print(f"[{i + 1}/{len(cases)}] {case.name}", flush=True)


def autocorrelation_curve(detail, ok, top=32):
    """The detail's normalised autocorrelation over the known pixels, averaged over the lags
    of each chessboard length 0..top whose overlap holds a quarter of the known pixels (an
    array; 0 where no lag of that length does)."""
    d = np.where(ok, detail, 0).astype(np.float64)
    k = ok.astype(np.float64)
    shape = (sfft.next_fast_len(d.shape[0] + top + 1), sfft.next_fast_len(d.shape[1] + top + 1))
    fd, fd2, fk = sfft.rfft2(np.stack([d, d * d, k]), shape)
    num, e1, e2, count = sfft.irfft2(
        np.stack([fd * np.conj(fd), fd2 * np.conj(fk), fk * np.conj(fd2), fk * np.conj(fk)]), shape
    )
    ty = sfft.fftfreq(shape[0], 1 / shape[0])[:, None]
    tx = sfft.fftfreq(shape[1], 1 / shape[1])[None, :]
    length = np.broadcast_to(np.maximum(np.abs(ty), np.abs(tx)), num.shape)
    use = (length <= top) & (count > 0.25 * k.sum()) & (np.minimum(e1, e2) > 1e-12)
    corr = np.zeros(num.shape)
    corr[use] = num[use] / np.sqrt(e1[use] * e2[use])
    total = np.bincount(length[use].astype(int), corr[use], minlength=top + 1)
    n = np.bincount(length[use].astype(int), minlength=top + 1)
    return np.where(n > 0, total / np.maximum(n, 1), 0.0)[: top + 1]


class Scored:
    """One cached case: each candidate's output, its clusters and their measures."""

    def __init__(self, case):
        from clpde.inpainting import choose, pick, smooth

        self.case = case
        job, box, data = _job(case)
        z = np.load(_path(case))
        omega = case.mask
        known = ~omega
        self.seconds = {k[4:]: float(z[k]) for k in z.files if k.startswith("sec_")}
        self.outs = {}
        for n in NAMES:
            filled = data.copy()
            filled[:, omega] = z[f"fill_hole_{n}"]
            img = case.damaged().copy()
            job._write(img, box, filled, omega)
            self.outs[n] = img
        parts = pick.clusters_of(omega)
        clusters, count, radius = parts
        self.clusters, self.count = clusters, count
        periodic = pick.periodic_clusters(data, omega, parts=parts)
        in_period = np.zeros(count + 1, bool)
        in_period[np.unique(clusters[periodic])] = True
        self.candidate = (radius >= pick.SMOOTH_RADIUS) & ~in_period[1:]
        dist, (iy, ix) = ndimage.distance_transform_edt(known, return_indices=True)
        owner = np.where(known, clusters[iy, ix], 0)
        detail, ok = choose._detail(data, known)
        labels = np.arange(1, count + 1)
        ring8 = np.where(known & (dist <= 8), owner, 0)
        texture = np.sqrt(np.nan_to_num(np.asarray(ndimage.mean(detail**2, ring8, labels), float)))
        m = {"radius": radius, "texture": texture}
        m["gap"], m["sep"] = pick.edge_contrast(data, omega, parts)
        rho, rough = np.zeros(count), np.full(count, np.inf)
        slices = ndimage.find_objects(clusters)
        cand = 1 + np.flatnonzero(self.candidate)
        t0 = time.process_time()
        rough[cand - 1] = pick.roughness(data, omega, parts, cand)
        self.seconds["roughness"] = time.process_time() - t0
        self.curves = np.zeros((count, 33))
        for k in cand - 1:
            w = smooth.grown_box(slices[k], pick.WINDOW, omega.shape)
            lag = int(np.clip(round(radius[k]), 1, 32))
            self.curves[k] = autocorrelation_curve(detail[w], ok[w])
            rho[k] = self.curves[k][lag]
        self.depth = ndimage.distance_transform_edt(omega)
        # the same over the 8 px ring's own spread instead of the window's
        grey = data.mean(axis=0)
        g1 = np.asarray(ndimage.mean(grey, ring8, labels), float)
        g2 = np.asarray(ndimage.mean(grey**2, ring8, labels), float)
        spread8 = np.sqrt(np.maximum(np.nan_to_num(g2 - g1**2), 1e-24))
        m["rough2"] = texture / spread8
        m["rho"], m["rough"] = rho, rough
        # ring errors: the host's biharmonic fill (smooth.ring_errors), the spectral fill's
        # from the cache
        ring_bih, spread = np.full(count, np.inf), np.ones(count)
        t0 = time.process_time()
        ring_bih[cand - 1], spread[cand - 1] = smooth.ring_errors(
            data, omega, clusters, cand, RING, (dist, owner)
        )
        self.seconds["ring_errors"] = time.process_time() - t0
        hidden = z["mask_ring"]
        index = np.full(hidden.shape, -1)
        index[hidden] = np.arange(int(hidden.sum()))
        sel = known & (dist <= RING)
        own = owner[sel]
        n_ring = np.maximum(np.bincount(own, minlength=count + 1)[1:], 1)
        sq = ((z["fill_ring_spectral"][:, index[sel]] - data[:, sel]) ** 2).mean(axis=0)
        m["ring_spectral"] = np.bincount(own, sq, minlength=count + 1)[1:] / n_ring
        det = np.bincount(own, detail[sel] ** 2, minlength=count + 1)[1:] / n_ring
        m["ring_biharmonic"] = ring_bih
        m["fit"] = ring_bih / np.maximum(det, 1e-12)
        m["fitvar"] = ring_bih / np.maximum(spread, 1e-15)
        m["ratio"] = ring_bih / np.maximum(m["ring_spectral"], 1e-15)
        # each candidate's squared error per cluster (in the output's units over the peak)
        lab = clusters[omega]
        size = np.maximum(np.bincount(lab, minlength=count + 1)[1:], 1)
        for n in NAMES:
            sq = (
                (self.outs[n][omega].astype(float) - case.truth[omega].astype(float)) / case.peak
            ) ** 2
            sq = sq.mean(axis=1) if sq.ndim > 1 else sq
            m[f"err_{n}"] = np.bincount(lab, sq, minlength=count + 1)[1:] / size
        self.m = m

    def route(self, smooth):
        """The case's PSNR with the clusters in `smooth` (bool per cluster) taken from the
        biharmonic fill; or, float per cluster, the biharmonic fill's weight in a blend with
        the default's; or ("depth", allowed) per pixel, the biharmonic fill's weight one
        minus the detail's autocorrelation at the pixel's depth (clipped to [0, 1]) on the
        clusters `allowed`."""
        omega = self.case.mask
        lab = self.clusters[omega]
        if isinstance(smooth, tuple):
            allowed = smooth[1] & self.candidate
            depth = np.minimum(np.rint(self.depth[omega]).astype(int), 32)
            rho = self.curves[lab - 1, depth]
            w = np.where(allowed[lab - 1], 1 - np.clip(rho, 0, 1), 0.0)
            if len(smooth) > 2:  # these clusters whole
                w = np.where((smooth[2] & self.candidate)[lab - 1], 1.0, w)
        else:
            w = np.where(self.candidate, np.asarray(smooth, float), 0.0)[lab - 1]
        a = self.outs["pick"][omega].astype(float)
        b = self.outs["biharmonic"][omega].astype(float)
        if a.ndim > 1:
            w = w[:, None]
        mix = a + w * (b - a)
        img = self.outs["pick"].copy()
        if np.issubdtype(img.dtype, np.integer):
            mix = np.rint(mix)
        img[omega] = mix.astype(img.dtype)
        return corpus.psnr(self.case, img)


def rules():
    out = {"default (today)": lambda m: np.zeros_like(m["radius"], bool)}
    out["oracle"] = lambda m: m["err_biharmonic"] < m["err_pick"]
    out["biharmonic everywhere"] = lambda m: np.ones_like(m["radius"], bool)
    for r in (0.8, 1.0):
        out[f"ring vote ratio < {r}"] = lambda m, r=r: m["ratio"] < r
    for t in (0.1, 0.2, 0.3, 0.4, 0.5, 0.6):
        out[f"rho < {t}"] = lambda m, t=t: m["rho"] < t
    for t in (0.05, 0.1, 0.15, 0.2, 0.25, 0.3, 0.4, 0.5):
        out[f"rough < {t}"] = lambda m, t=t: m["rough"] < t
    for t in (0.1, 0.2, 0.3, 0.4, 0.5):
        out[f"rough2 < {t}"] = lambda m, t=t: m["rough2"] < t
    for t in (0.2, 0.3):
        for q in (3, 5):
            out[f"rough < {t} & fit < {q}"] = lambda m, t=t, q=q: (m["rough"] < t) & (m["fit"] < q)
    for q in (1.5, 2, 3, 5, 10):
        out[f"fit < {q}"] = lambda m, q=q: m["fit"] < q
    for q in (0.01, 0.03, 0.1, 0.3):
        out[f"fitvar < {q}"] = lambda m, q=q: m["fitvar"] < q
    for w in (0.3, 0.5, 0.7):
        out[f"blend {w} biharmonic"] = lambda m, w=w: np.full(m["radius"].shape, w)
    out["blend by depth's rho"] = lambda m: ("depth", np.ones(m["radius"].shape, bool))
    for t in (0.2, 0.3):
        out[f"rough < {t}, else blend by depth"] = lambda m, t=t: (
            "depth",
            np.ones(m["radius"].shape, bool),
            m["rough"] < t,
        )
    for r in (4, 6, 8, 10):
        out[f"radius >= {r}"] = lambda m, r=r: m["radius"] >= r
    for r in (4, 6, 8):
        for t in (0.2, 0.4):
            out[f"radius >= {r} & rho < {t}"] = lambda m, r=r, t=t: (
                (m["radius"] >= r) & (m["rho"] < t)
            )
        for q in (2, 3, 5):
            out[f"radius >= {r} & fit < {q}"] = lambda m, r=r, q=q: (
                (m["radius"] >= r) & (m["fit"] < q)
            )
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("what", choices=("cache", "rules"))
    parser.add_argument("--half", default="both")
    parser.add_argument("--clusters", action="store_true")
    parser.add_argument("--only", default=None, help="comma-separated case names (cache)")
    parser.add_argument("--not-edge", action="store_true", help="leave clear edges (pick.EDGE_*)")
    args = parser.parse_args(argv)
    halves = ("calibration", "test") if args.half == "both" else (args.half,)
    if args.what == "cache":
        return cache(halves, args.only)
    from clpde.inpainting import pick

    rows = [
        Scored(c)
        for c in corpus.build()
        if c.half in halves and _path(c).exists() and (not args.only or c.name in args.only)
    ]
    if args.clusters:
        for s in rows:
            m = s.m
            for k in np.flatnonzero(s.candidate):
                gain = 10 * np.log10(
                    max(m["err_pick"][k], 1e-16) / max(m["err_biharmonic"][k], 1e-16)
                )
                print(
                    f"{s.case.half[:3]} {s.case.name:30s} {k + 1:3d} r={m['radius'][k]:4.1f} "
                    f"tex={m['texture'][k]:.4f} rho={m['rho'][k]:5.2f} rough={m['rough'][k]:.3f} "
                    f"r2={m['rough2'][k]:.3f} "
                    f"fit={m['fit'][k]:6.2f} fv={m['fitvar'][k]:.3f} ratio={m['ratio'][k]:5.2f} "
                    f"gap={m['gap'][k]:.2f} "
                    f"sep={m['sep'][k]:4.1f}  bih-pick={gain:+6.2f} dB"
                )
    for half in halves:
        sel = [s for s in rows if s.case.half == half]
        print(f"\n{half} ({len(sel)} cases): rule | mean over classes | per class")
        for label, rule in rules().items():
            by, routed = {}, {}
            for s in sel:
                smooth = rule(s.m)
                edge = (s.m["gap"] >= pick.EDGE_GAP) & (s.m["sep"] >= pick.EDGE_SEPARATION)
                if isinstance(smooth, tuple):
                    keep = ~edge if args.not_edge else np.ones_like(edge)
                    smooth = tuple(x if isinstance(x, str) else x & keep for x in smooth)
                    n = int((smooth[1] & s.candidate).sum())
                else:
                    smooth = np.where(edge, 0, smooth) if args.not_edge else smooth
                    n = int(((np.asarray(smooth, float) > 0) & s.candidate).sum())
                by.setdefault(s.case.damage, []).append(s.route(smooth))
                routed[s.case.damage[:2]] = routed.get(s.case.damage[:2], 0) + n
            means = {d: np.mean(v) for d, v in by.items()}
            print(
                f"{label:30s} {np.mean(list(means.values())):6.2f}  "
                + " ".join(f"{d[:5]}={means[d]:.2f}" for d in corpus.CLASSES if d in means)
                + "  routed "
                + ",".join(f"{k}{v}" for k, v in routed.items() if v)
            )
        secs = {}
        for s in sel:
            for k, v in s.seconds.items():
                secs.setdefault(s.case.damage, {}).setdefault(k, 0.0)
                secs[s.case.damage][k] += v
        for d in corpus.CLASSES:
            if d in secs:
                print(f"  {d:11s} " + " ".join(f"{k}={v:.2f}" for k, v in sorted(secs[d].items())))


if __name__ == "__main__":
    main()
