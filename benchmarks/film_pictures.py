"""docs/images/film_people.png: before | after of walking people from the TEST half
(vtest a of benchmarks/film_corpus.py), detect_defects + inpaint_video with the defaults
and keep=KEEP, as `clpde restore`.

    python benchmarks/film_pictures.py
"""

from __future__ import annotations

from pathlib import Path

import cv2
import numpy as np
from film_corpus import corpus

import clpde
from clpde.film.stream import KEEP

OUT = Path(__file__).resolve().parents[1] / "docs" / "images" / "film_people.png"


def main():
    c = corpus("test", frames=12)[0]
    d = c["dirty"]
    mask, kinds = clpde.detect_defects(d, channel_axis=-1, return_kinds=True)
    out = clpde.inpaint_video(d, mask, channel_axis=-1, keep=KEEP, kinds=kinds)
    rows = []
    for t in (0, 6, 11):  # the first, a middle and the last frame
        crop = (slice(40, 200), slice(100, 380))
        rows.append(np.concatenate([d[t][crop], out[t][crop]], axis=1))
        rows.append(np.full((4, rows[-1].shape[1], 3), 255, np.uint8))
    img = np.concatenate(rows[:-1], axis=0)
    img = cv2.resize(img, None, fx=2, fy=2, interpolation=cv2.INTER_NEAREST)
    OUT.parent.mkdir(parents=True, exist_ok=True)
    cv2.imwrite(str(OUT), cv2.cvtColor(img, cv2.COLOR_RGB2BGR))
    print("wrote", OUT)


if __name__ == "__main__":
    main()
