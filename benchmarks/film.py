"""Film restoration on real footage with synthetic damage (benchmarks/film_corpus.py).

    python benchmarks/film.py [--frames 16] [--sweep] [--json PATH] [--half calibration]
        [--more]

Test half (vtest, Megamind) and calibration half (tree, carphone), each clip 16 frames.
For each: clpde.detect_defects + clpde.inpaint_video with the defaults, and the peers:

- inpaint_video given the TRUE masks;
- clpde.inpaint frame by frame given the TRUE masks (the spatial peer);
- OpenCV Telea frame by frame given the TRUE masks, and given the detected masks;
- SDI (Kokaram's spike detection index, 3 frames compensated by DIS, 20 grey levels) +
  a temporal median of the 3 compensated frames at what it flags.

Do-no-harm figures: the share of pixels outside the damage (outside everything the damage
touched) changed by more than 10 grey levels, per frame: its worst frame, and its worst at
a clip's first and last frames; frames whose PSNR against the clean frame fell below the
damaged input's. --half runs one half only; --more widens the calibration half with
film_corpus.CALIBRATION_MORE (the default table keeps the four clips). --sweep prints the
calibration half's detection at other blotch thresholds (from one evidence computation per
clip).
"""

from __future__ import annotations

import argparse
import json
import time

import cv2
import numpy as np
from film_corpus import corpus

import clpde
from clpde.film import detect as fdet
from clpde.film._planes import film_planes, grey
from clpde.film.stream import KEEP
from clpde.motion.dis import DisFlow, to_u8


class Counts:
    def __init__(self):
        self.tp = self.fp = self.fn = 0

    def add(self, det, gt, other_damage, spare):
        """Detections on spare pixels count neither way; a blotch found on a scratch (or the
        reverse) is not a false alarm (it is damage, and filled)."""
        det = det & ~spare
        gt = gt & ~spare
        self.tp += int((det & gt).sum())
        self.fp += int((det & ~gt & ~other_damage).sum())
        self.fn += int((~det & gt).sum())

    def pr(self):
        p = self.tp / max(self.tp + self.fp, 1)
        r = self.tp / max(self.tp + self.fn, 1)
        return p, r


def psnr(a, b, sel=None):
    d = (a.astype(np.float64) - b.astype(np.float64)) ** 2
    d = d.mean(-1)
    if sel is not None:
        d = d[sel]
    return 10 * np.log10(255.0**2 / max(float(d.mean()) if d.size else 0.0, 1e-10))


class Quality:
    """Pooled PSNR (whole frames, damaged pixels), harm per frame, frames made worse."""

    def __init__(self):
        self.se = {"whole": 0.0, "damaged": 0.0}
        self.n = {"whole": 0, "damaged": 0}
        self.harm, self.harm_end, self.worse = 0.0, 0.0, 0

    def add(self, out, clip):
        clean, dirty, truth, spare = clip["clean"], clip["dirty"], clip["truth"], clip["spare"]
        d2 = ((out.astype(np.float64) - clean.astype(np.float64)) ** 2).mean(-1)
        for key, sel in (("whole", np.ones(truth.shape, bool)), ("damaged", truth > 0)):
            self.se[key] += float(d2[sel].sum())
            self.n[key] += int(sel.sum())
        T = len(out)
        outside = (truth == 0) & ~spare
        changed = np.abs(out.astype(int) - dirty.astype(int)).max(-1) > 10
        for t in range(T):
            share = float((changed[t] & outside[t]).sum()) / outside[t].size
            self.harm = max(self.harm, share)
            if t in (0, T - 1):
                self.harm_end = max(self.harm_end, share)
            if psnr(out[t], clean[t]) < psnr(dirty[t], clean[t]) - 1e-9:
                self.worse += 1

    def row(self):
        p = {
            k: 10 * np.log10(255.0**2 / max(self.se[k] / max(self.n[k], 1), 1e-10)) for k in self.se
        }
        return (
            f"{p['whole']:.2f} | {p['damaged']:.2f} | {100 * self.harm:.2f}% | "
            f"{100 * self.harm_end:.2f}% | {self.worse}"
        )


def sdi_median(dirty, level=20):
    """SDI on DIS-compensated neighbours, then the temporal median of the three."""
    dis = DisFlow()
    G = grey(film_planes(dirty, -1)[0])
    out = dirty.copy()
    flags = np.zeros(G.shape, bool)
    for t in range(1, len(G) - 1):
        ws, cs = [], []
        for s in (t - 1, t + 1):
            f = dis.flow(to_u8(G[t]), to_u8(G[s]))
            ws.append(dis.warp(G[s], f))
            cs.append(dis.warp(dirty[s].astype(np.float32), f))
        dp, dn = G[t] - ws[0], G[t] - ws[1]
        sdi = np.where(np.sign(dp) == np.sign(dn), np.minimum(abs(dp), abs(dn)), 0) * 255
        m = sdi > level
        med = np.median(np.stack([cs[0], dirty[t].astype(np.float32), cs[1]]), axis=0)
        out[t][m] = np.rint(med[m]).astype(np.uint8)
        flags[t] = m
    return out, flags


def spatial(frames, masks, method):
    out = frames.copy()
    for t in range(len(frames)):
        if masks[t].any():
            if method == "telea":
                out[t] = cv2.inpaint(frames[t], masks[t].astype(np.uint8), 3, cv2.INPAINT_TELEA)
            else:
                out[t] = clpde.inpaint(frames[t], masks[t], channel_axis=-1)
    return out


def run_half(half, frames, more=False):
    clips = corpus(half, frames=frames, more=more)
    det = {"blotch": Counts(), "scratch": Counts(), "sdi": Counts()}
    names = [
        "detect_defects + inpaint_video",
        "inpaint_video, true masks",
        "clpde.inpaint per frame, true masks",
        "OpenCV Telea per frame, true masks",
        "OpenCV Telea per frame, detected masks",
        "SDI + temporal median of 3",
        "damaged input",
    ]
    q = {n: Quality() for n in names}
    seconds = {"detect": 0.0, "fill": 0.0, "pixels": 0}
    per_clip = []
    for c in clips:
        d, truth, spare = c["dirty"], c["truth"], c["spare"]
        t0 = time.perf_counter()
        mask, kinds = clpde.detect_defects(d, channel_axis=-1, return_kinds=True)
        t1 = time.perf_counter()
        out = clpde.inpaint_video(d, mask, channel_axis=-1, keep=KEEP, kinds=kinds)
        t2 = time.perf_counter()
        seconds["detect"] += t1 - t0
        seconds["fill"] += t2 - t1
        seconds["pixels"] += d.shape[0] * d.shape[1] * d.shape[2]
        det["blotch"].add(kinds == 1, truth == 1, truth == 2, spare)
        det["scratch"].add(kinds == 2, truth == 2, truth == 1, spare)
        sdi_out, flags = sdi_median(d)
        det["sdi"].add(flags, truth == 1, truth == 2, spare)
        gt = truth > 0
        outs = [
            out,
            clpde.inpaint_video(d, gt, channel_axis=-1),
            spatial(d, gt, "clpde"),
            spatial(d, gt, "telea"),
            spatial(d, mask, "telea"),
            sdi_out,
            d,
        ]
        one = Quality()
        one.add(out, c)
        tm, sm = Quality(), Quality()
        tm.add(outs[1], c)
        sm.add(outs[2], c)
        cb, cs = Counts(), Counts()
        cb.add(kinds == 1, truth == 1, truth == 2, spare)
        cs.add(kinds == 2, truth == 2, truth == 1, spare)
        given = (
            f"true masks, damaged px: temporal {tm.row().split(' | ')[1]}, "
            f"spatial {sm.row().split(' | ')[1]}"
        )
        per_clip.append((c["name"], cb.pr(), cs.pr(), one.row() + " | " + given))
        for n, o in zip(names, outs, strict=True):
            q[n].add(o, c)
    return det, q, seconds, per_clip, clips


def report(half, det, q, seconds, per_clip, frames):
    print(f"\n### {half.capitalize()} half, {len(per_clip)} clips x {frames} frames\n")
    print("| detector | precision | recall |\n|---|---|---|")
    for k, label in (
        ("blotch", "detect_defects, blotches"),
        ("scratch", "detect_defects, line scratches"),
        ("sdi", "SDI (20 levels), blotches"),
    ):
        p, r = det[k].pr()
        print(f"| {label} | {p:.3f} | {r:.3f} |")
    print(
        "\n| restoration | PSNR whole | PSNR damaged px | harm: worst frame | "
        "harm: worst end frame | frames worse than input |\n|---|---|---|---|---|---|"
    )
    for n, qq in q.items():
        print(f"| {n} | {qq.row()} |")
    px = seconds["pixels"] / (640 * 360)
    print(
        f"\nseconds per 640x360-equivalent frame: detect {seconds['detect'] / px:.2f}, "
        f"fill {seconds['fill'] / px:.2f}"
    )
    print("\nper clip: blotch P/R, scratch P/R | PSNR whole, damaged, harm, harm ends, worse")
    for name, b, s, row in per_clip:
        print(f"- {name}: {b[0]:.2f}/{b[1]:.2f}, {s[0]:.2f}/{s[1]:.2f} | {row}")


def sweep(clips):
    print("\ncalibration sweep (blotch threshold: P/R)")
    grids = [4.0, 6.0, 8.0, 10.0, 12.0]
    counts = {b: Counts() for b in grids}
    for c in clips:
        G = grey(film_planes(c["dirty"], -1)[0])
        sc = fdet.film_scores(G, None, 2)
        ml = max(24, int(0.4 * G.shape[1]))
        for b in grids:
            k = fdet.film_kinds(G, sc, b, fdet.SCRATCH_THRESHOLD, 24, ml)
            counts[b].add(k == 1, c["truth"] == 1, c["truth"] == 2, c["spare"])
    for b in grids:
        print(f"  {b}: {counts[b].pr()[0]:.3f}/{counts[b].pr()[1]:.3f}")


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--frames", type=int, default=16)
    ap.add_argument("--sweep", action="store_true")
    ap.add_argument("--json", default=None)
    ap.add_argument("--half", choices=("test", "calibration"), default=None)
    ap.add_argument("--more", action="store_true")
    args = ap.parse_args()
    results = {}
    for half in ("test", "calibration"):
        if args.half not in (None, half):
            continue
        det, q, seconds, per_clip, clips = run_half(half, args.frames, args.more)
        report(half, det, q, seconds, per_clip, args.frames)
        results[half] = {k: v.pr() for k, v in det.items()}
        if half == "calibration" and args.sweep:
            sweep(clips)
    if args.json:
        with open(args.json, "w") as fh:
            json.dump(results, fh, indent=1)


if __name__ == "__main__":
    main()
