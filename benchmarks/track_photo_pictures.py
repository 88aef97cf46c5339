"""Overlays of test-half clips of benchmarks/track_photo_corpus.py for docs/tracking.md:
per row one clip at four frames, the default (kalman + adaptive, blue), motion='image'
(red) and the truth (green).

    python benchmarks/track_photo_pictures.py       # writes docs/images/track_photo_test.png
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

CLIPS = (("fast", 1), ("occlude", 1), ("clutter", 3), ("pan", 3))
FRAMES = (1, 5, 10, 15)


def _outline(img, mask, colour):
    edge = mask ^ ndimage.binary_erosion(mask)
    img[edge] = colour


def main():
    from skimage.io import imsave

    import clpde

    rows = []
    for cls, seed in CLIPS:
        frames, truth = MAKERS[cls](seed)
        default = clpde.track(frames, truth[0], progress=False)
        image = clpde.track(frames, truth[0], motion="image", progress=False)
        colour = frames if frames.ndim == 4 else np.repeat(frames[..., None], 3, -1)
        tiles = []
        for t in FRAMES:
            img = colour[t].copy()
            _outline(img, truth[t], (0, 1, 0))
            _outline(img, default[t], (0, 0.4, 1))
            _outline(img, image[t], (1, 0, 0))
            tiles.append(np.pad(img, ((1, 1), (1, 1), (0, 0)), constant_values=1))
        rows.append(np.concatenate(tiles, 1))
    out = ROOT / "docs" / "images" / "track_photo_test.png"
    picture = np.concatenate(rows, 0)
    imsave(out, (np.clip(picture, 0, 1) * 255).astype(np.uint8))
    print(f"wrote {out}")


if __name__ == "__main__":
    main()
