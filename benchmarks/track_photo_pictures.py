"""Overlays of test-half clips of benchmarks/track_photo_corpus.py for docs/tracking.md:
per row one clip at four frames, motion='checked' (the default before, blue), the default
(motion='image', red) and the truth (green); tiles cropped around the truth.

    python benchmarks/track_photo_pictures.py       # writes docs/images/track_photo_test.png
    python benchmarks/track_photo_pictures.py --checked  # docs/images/track_checked.png

With --checked: motion='kalman' (blue) against motion='checked' (red) on the
real footage (vtest walkers, test clip then calibration clip; tiles cropped around the
truth) and a test-half composite of the fast class.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np
from scipy import ndimage

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from track_photo_corpus import MAKERS  # noqa: E402

CLIPS = (("fast", 1), ("occlude", 1), ("clutter", 3), ("pan", 3), ("footage", 1))
FRAMES = (1, 5, 10, 15)


def _outline(img, mask, colour):
    edge = mask ^ ndimage.binary_erosion(mask)
    img[edge] = colour


CHECKED_CLIPS = (("footage", 1, (1, 4, 8, 12, 15)), ("footage", 0, (1, 3, 5, 7, 9)))
CHECKED_CLIPS += (("fast", 1, (1, 4, 8, 12, 15)),)
TILE = (150, 144)


def _tile(img, centre):
    """A TILE-sized crop of img about `centre` (within the frame), padded with white."""
    h, w = TILE
    y0 = int(np.clip(round(centre[0]) - h // 2, 0, max(img.shape[0] - h, 0)))
    x0 = int(np.clip(round(centre[1]) - w // 2, 0, max(img.shape[1] - w, 0)))
    crop = img[y0 : y0 + h, x0 : x0 + w]
    pad = ((0, h - crop.shape[0]), (0, w - crop.shape[1]), (0, 0))
    return np.pad(np.pad(crop, pad, constant_values=1), ((1, 1), (1, 1), (0, 0)), constant_values=1)


def _picture(clips, blue: dict, red: dict, name: str) -> None:
    """One row per (class, seed, frames) clip: truth green, clpde.track(**blue) blue and
    clpde.track(**red) red, each frame a tile cropped around the truth; to docs/images/name."""
    from skimage.io import imsave

    import clpde

    rows = []
    for cls, seed, chosen in clips:
        frames, truth = MAKERS[cls](seed)
        first = clpde.track(frames, truth[0], progress=False, **blue)
        second = clpde.track(frames, truth[0], progress=False, **red)
        colour = frames if frames.ndim == 4 else np.repeat(frames[..., None], 3, -1)
        tiles = []
        for t in chosen:
            img = colour[t].copy()
            _outline(img, truth[t], (0, 1, 0))
            _outline(img, first[t], (0, 0.4, 1))
            _outline(img, second[t], (1, 0, 0))
            tiles.append(_tile(img, ndimage.center_of_mass(truth[t])))
        rows.append(np.concatenate(tiles, 1))
    out = ROOT / "docs" / "images" / name
    imsave(out, (np.clip(np.concatenate(rows, 0), 0, 1) * 255).astype(np.uint8))
    print(f"wrote {out}")


def main():
    if "--checked" in sys.argv[1:]:
        _picture(CHECKED_CLIPS, {"motion": "kalman"}, {"motion": "checked"}, "track_checked.png")
    else:
        clips = [(cls, seed, FRAMES) for cls, seed in CLIPS]
        _picture(clips, {"motion": "checked"}, {}, "track_photo_test.png")


if __name__ == "__main__":
    main()
