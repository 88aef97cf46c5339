"""Real footage with large motion for the tracking corpus (issue 35): walkers in opencv-doc's
vtest.avi (a static camera, 768x576, 10 frames a second), every second frame, so that
they move 16-22 px a frame, in crops around their paths.

    python benchmarks/track_footage.py --masks     # (re)build the masks from the video
    python benchmarks/track_footage.py --sheet P   # a contact sheet to check them by eye
    python benchmarks/track_footage.py --masks --keep-shadow --out DIR  # the old truth
    TRACK_FOOTAGE_MASKS=DIR python benchmarks/tracking_generalise.py ...  # scored on it
    python benchmarks/track_footage.py --truth-picture DIR P  # old against new, for the docs

The masks in benchmarks/data/vtest/<clip>/NNN.png (one per frame of the clip, the walker
white) were made by background subtraction, not by hand: the camera does not move, so the
median of every 5th frame of the whole video is the empty street; a pixel is the walker's
where some channel differs from it by more than THRESHOLD grey levels, cleaned by an
opening and a closing, holes filled, less the pixels within THRESHOLD of the street
(the pole in front of the walker, the road between the legs), keeping the pieces (over 30
px) within NEAR px of the walker's previous mask (or the one holding the clip's seed
point), and, since issue 35's tracktruth round, less the walker's cast shadow on the ground
(tests/cases/cast_shadow.py: darker than the street by a factor of 0.6-0.95, the street's
colour, a ratio to it that changes slowly, in the bottom quarter of the walker's height).
They were then checked by eye on the contact sheet (and frame by frame at 2x and 4x): each
covers the walker, head to feet, with no other walker and not the pole in front of walker
B at the clip's end. Before the shadow rule the soft shadow at the feet (the day is
overcast) was in the masks, 6-14% of walker A's mask; ``--keep-shadow`` makes those masks
again, bit for bit (docs/tracking.md, "The footage truth without the cast shadow").

Clip 0 (walker A, frames 0-18) is in the calibration half, clip 1 (walker B, frames
220-250, another stretch of the video) in the test half. Clip 2 (calibration, added by
issue 35's trackfoot round: the calibration half's one clip had 10 frames): a woman in a
dark coat and jeans crossing the grass near the camera, frames 600-630, standing, then
walking 9-18 px a frame and turning away; her feet at the frame's lower edge. Its masks,
made as the others', were checked by eye at 2x, every frame: head to feet, nothing of the
grass or the yellow cloth beside her; a few px of her hair's edge are missing where it
looks like the lawn.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))  # tests.cases
from tests.cases.cast_shadow import without_cast_shadow  # noqa: E402

VIDEO = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")
MASKS = Path(__file__).resolve().parent / "data" / "vtest"
# another truth to score on (a folder of clip<seed>/NNN.png, e.g. --keep-shadow's)
MASKS_ENV = "TRACK_FOOTAGE_MASKS"
THRESHOLD = 35
NEAR = 12  # px: a piece this close to the walker's previous mask is the walker's
# seed: clip -> (first frame, frames, step, (row0, row1, col0, col1) crop, (row, col) of a
# pixel of the walker in the first frame, full-resolution coordinates)
CLIPS = {
    0: (0, 10, 2, (180, 380, 400, 720), (282, 662)),
    1: (220, 16, 2, (180, 440, 280, 660), (350, 604)),
    # a woman in a dark coat crossing the grass near the camera (feet at the frame's edge)
    2: (600, 16, 2, (376, 576, 230, 510), (500, 306)),
}


def _video() -> np.ndarray:
    import cv2

    if not VIDEO.exists():
        raise SystemExit(f"{VIDEO} is missing: apt-get install opencv-doc")
    cap = cv2.VideoCapture(str(VIDEO))
    out = []
    while True:
        ok, frame = cap.read()
        if not ok:
            break
        out.append(frame[..., ::-1])  # BGR -> RGB
    return np.array(out)


def frames(seed: int, video: np.ndarray | None = None) -> np.ndarray:
    """Clip `seed`'s frames, (T, H, W, 3) float64 in [0, 1]."""
    import cv2

    start, count, step, (r0, r1, c0, c1), _ = CLIPS[seed]
    if video is None:
        cap = cv2.VideoCapture(str(VIDEO))
        if not VIDEO.exists():
            raise SystemExit(f"{VIDEO} is missing: apt-get install opencv-doc")
        cap.set(cv2.CAP_PROP_POS_FRAMES, start)
        picked = []
        for k in range((count - 1) * step + 1):
            ok, frame = cap.read()
            if not ok:
                raise SystemExit(f"{VIDEO} ended at frame {start + k}")
            if k % step == 0:
                picked.append(frame[..., ::-1])
        clip = np.array(picked)
    else:
        clip = video[start : start + count * step : step]
    return clip[:, r0:r1, c0:c1].astype(np.float64) / 255.0


def build_masks(seeds=None, keep_shadow: bool = False, out: Path = MASKS) -> None:
    """Write the masks of the clips `seeds` (default: all) from background subtraction
    (see the module's note) into `out`; `keep_shadow`: the masks before the shadow rule."""
    from skimage.io import imsave

    video = _video()
    background = np.median(video[::5].astype(np.float32), axis=0)
    for seed, (_start, _count, _step, (r0, r1, c0, c1), point) in CLIPS.items():
        if seeds is not None and seed not in seeds:
            continue
        clip = frames(seed, video) * 255.0
        bg = background[r0:r1, c0:c1]
        previous = None
        folder = Path(out) / f"clip{seed}"
        folder.mkdir(parents=True, exist_ok=True)
        for t, frame in enumerate(clip):
            diff = np.abs(frame - bg).max(axis=-1)
            fg = diff > THRESHOLD
            fg = ndimage.binary_closing(ndimage.binary_opening(fg), iterations=2)
            fg = ndimage.binary_fill_holes(fg)
            labels, _ = ndimage.label(fg)
            if previous is None:
                keep = {labels[point[0] - r0, point[1] - c0]} - {0}
            else:
                # pieces near the last mask: a walker cut in two by the pole stays whole
                near = ndimage.binary_dilation(previous, iterations=NEAR)
                keep = {k for k in set(np.unique(labels[near])) - {0} if (labels == k).sum() > 30}
            mask = np.isin(labels, list(keep)) if keep else np.zeros_like(fg)
            # the closing bridged the pole in front of the walker and the road between the
            # legs: what looks like the empty street is not the walker (small holes are)
            mask &= diff > THRESHOLD
            holes = ndimage.binary_fill_holes(mask) & ~mask
            labels, _ = ndimage.label(holes)
            mask |= (np.bincount(labels.ravel()) < 30)[labels] & holes
            previous = mask  # the walker's place, found with its shadow as before
            if not keep_shadow:
                mask = without_cast_shadow(frame, bg, mask)
            imsave(folder / f"{t:03d}.png", (mask * 255).astype(np.uint8), check_contrast=False)
        print(f"clip {seed}: {len(clip)} masks in {folder}")


def clip(seed: int, masks: Path | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Clip `seed`'s frames (T, H, W, 3) float64 in [0, 1] and masks (T, H, W) bool (from
    the folder `masks`, else $TRACK_FOOTAGE_MASKS, else the corpus' own)."""
    import os

    from skimage.io import imread

    f = frames(seed)
    folder = Path(masks or os.environ.get(MASKS_ENV) or MASKS) / f"clip{seed}"
    masks = np.array([imread(folder / f"{t:03d}.png") > 127 for t in range(len(f))])
    return f, masks


def sheet(path: Path) -> None:
    """Every clip's frames with their masks' outlines in green, a row per clip."""
    from skimage.io import imsave
    from skimage.segmentation import find_boundaries

    rows = []
    for seed in CLIPS:
        f, masks = clip(seed)
        tiles = []
        for t in range(0, len(f), max(1, len(f) // 5))[:5]:
            tile = f[t].copy()
            tile[find_boundaries(masks[t], mode="outer")] = (0, 1, 0)
            tiles.append(tile)
        row = np.concatenate(tiles, axis=1)
        rows.append(row)
    width = max(r.shape[1] for r in rows)
    rows = [np.pad(r, ((0, 4), (0, width - r.shape[1]), (0, 0)), constant_values=1) for r in rows]
    imsave(path, (np.concatenate(rows) * 255).astype(np.uint8), check_contrast=False)


# the docs' picture: frames of the calibration clips where the shadow was (footage-0) and
# where the rule finds none (footage-2, the lawn)
PICTURE = ((0, (1, 3, 6, 7)), (2, (5, 12)))


def truth_picture(path: Path, old: Path, scale: int = 2) -> None:
    """The lower half of the walker in the frames of PICTURE at `scale`x, a row per clip:
    the frame, then what the shadow rule took out of the old masks (in folder `old`, made
    with --keep-shadow) in red and the new mask's outline in green."""
    from skimage.io import imsave
    from skimage.segmentation import find_boundaries

    rows = []
    for seed, picked in PICTURE:
        f, new = clip(seed)
        _, before = clip(seed, old)
        tiles = []
        for t in picked:
            r, c = np.nonzero(before[t])
            r0, r1 = (r.min() + r.max()) // 2, min(r.max() + 6, f.shape[1])
            c0, c1 = max(c.min() - 6, 0), c.max() + 7
            up = np.ones((scale, scale))
            frame = np.kron(f[t, r0:r1, c0:c1], up[..., None])
            shown = frame.copy()
            cut = np.kron(before[t, r0:r1, c0:c1] & ~new[t, r0:r1, c0:c1], up) > 0
            shown[cut] = 0.4 * shown[cut] + 0.6 * np.array((1.0, 0.1, 0.1))
            edge = find_boundaries(np.kron(new[t, r0:r1, c0:c1], up) > 0, mode="inner")
            shown[edge] = (0.1, 1.0, 0.1)
            gap = np.ones((frame.shape[0], 2, 3))
            tiles.append(
                np.pad(
                    np.concatenate([frame, gap, shown], axis=1),
                    ((0, 0), (0, 8), (0, 0)),
                    constant_values=1,
                )
            )
        height = max(t.shape[0] for t in tiles)
        tiles = [
            np.pad(t, ((0, height - t.shape[0]), (0, 0), (0, 0)), constant_values=1) for t in tiles
        ]
        rows.append(np.concatenate(tiles, axis=1))
    width = max(r.shape[1] for r in rows)
    rows = [np.pad(r, ((0, 6), (0, width - r.shape[1]), (0, 0)), constant_values=1) for r in rows]
    imsave(path, (np.concatenate(rows) * 255).astype(np.uint8), check_contrast=False)


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "--masks", nargs="*", type=int, default=None, help="rebuild the masks (of these clips)"
    )
    parser.add_argument(
        "--keep-shadow", action="store_true", help="the masks before the shadow rule"
    )
    parser.add_argument("--out", type=Path, default=MASKS, help="where --masks writes")
    parser.add_argument("--sheet", type=Path, default=None, help="write a contact sheet")
    parser.add_argument(
        "--truth-picture",
        nargs=2,
        type=Path,
        metavar=("OLD", "PNG"),
        help="the docs' picture of the shadow rule, against the --keep-shadow masks in OLD",
    )
    args = parser.parse_args(argv)
    if args.masks is not None:
        build_masks(args.masks or None, args.keep_shadow, args.out)
    if args.sheet:
        sheet(args.sheet)
    if args.truth_picture:
        truth_picture(args.truth_picture[1], args.truth_picture[0])
    for seed in CLIPS:
        _f, masks = clip(seed)
        c = [np.array(np.nonzero(m)).mean(axis=1) for m in masks]
        step = [float(np.hypot(*(b - a))) for a, b in zip(c, c[1:], strict=False)]
        print(
            f"clip {seed}: {masks.shape}, area {masks.sum((1, 2)).min()}-"
            f"{masks.sum((1, 2)).max()}, px/frame {min(step):.1f}-{max(step):.1f}"
        )


if __name__ == "__main__":
    sys.exit(main())
