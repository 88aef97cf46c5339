"""Which detections make a restored frame worse than its damaged input: on one half of
benchmarks/film_corpus.py, detect_defects + inpaint_video (keep as `clpde restore`), and
for every frame each detected component whose repair raised the squared error against the
clean frame, with its size, the share of it that is true damage and its kind; frames whose
harm (pixels outside the damage changed by more than 10 levels) passes 0.5% are listed too.

    PYTHONPATH=. python benchmarks/film_worse.py [--half calibration] [--frames 12] [--more]

(--more: the calibration half widened with film_corpus.CALIBRATION_MORE; --scan: instead,
film_corpus.calibration_scan()'s 56 windows of the calibration sources, 12 frames each fit.)

(The frames worse than their input on the calibration half lost to small false alarms,
4-23 px, on tree.avi's textured, motion-blurred foliage: what the tail check of
clpde/film/_regions.py refuses.)
"""

from __future__ import annotations

import argparse

import numpy as np
from film import psnr
from film_corpus import calibration_scan, corpus, make_clip
from scipy import ndimage

import clpde
from clpde.film.stream import KEEP


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--half", default="calibration")
    ap.add_argument("--frames", type=int, default=12)
    ap.add_argument("--more", action="store_true")
    ap.add_argument("--scan", action="store_true")
    args = ap.parse_args()
    if args.scan:
        clips = (make_clip(*spec, frames=args.frames) for spec in calibration_scan())
    else:
        clips = corpus(args.half, frames=args.frames, more=args.more)
    for c in clips:
        clean, dirty, truth = c["clean"], c["dirty"], c["truth"]
        mask, kinds = clpde.detect_defects(dirty, channel_axis=-1, return_kinds=True)
        out = clpde.inpaint_video(dirty, mask, channel_axis=-1, keep=KEEP, kinds=kinds)
        e_out = ((out.astype(float) - clean) ** 2).mean(-1)
        e_in = ((dirty.astype(float) - clean) ** 2).mean(-1)
        T = len(dirty)
        outside = (truth == 0) & ~c["spare"]
        changed = np.abs(out.astype(int) - dirty.astype(int)).max(-1) > 10
        for t in range(T):
            worse = psnr(out[t], clean[t]) < psnr(dirty[t], clean[t]) - 1e-9
            labels, _ = ndimage.label(kinds[t] > 0)
            rows = []
            for idx, sl in enumerate(ndimage.find_objects(labels), start=1):
                own = labels[sl] == idx
                gain = float((e_out[t][sl] - e_in[t][sl])[own].sum())
                if gain > 0:
                    true = float((truth[t][sl][own] > 0).mean())
                    rows.append((gain, int(own.sum()), true, int(kinds[t][sl][own].max()), sl))
            harm = float((changed[t] & outside[t]).mean())
            if not (worse or rows or harm > 0.005):  # the bar: 0.5% of a frame
                continue
            end = " (end)" if t in (0, T - 1) else ""
            total = float((e_out[t] - e_in[t]).sum())
            print(
                f"{c['name']} frame {t}{end}: worse {worse}, harm {100 * harm:.2f}%, "
                f"squared error change {total:+.0f}"
            )
            for gain, n, true, kind, sl in sorted(rows, key=lambda r: -r[0])[:6]:
                print(
                    f"    +{gain:.0f}: {n} px, {true:.2f} true, kind {kind}, "
                    f"at y {sl[0].start} x {sl[1].start}"
                )


if __name__ == "__main__":
    main()
