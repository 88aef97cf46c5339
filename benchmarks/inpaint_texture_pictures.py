"""Before/after pictures of the texture methods beside scikit-image's biharmonic fill.

    python benchmarks/inpaint_texture_pictures.py [OUT_DIR]   (default docs/images)

Writes inpaint_texture.png (texture cases) and inpaint_thick.png (thick holes in photos):
one row per case, cropped around the holes: the damaged image (holes in black),
biharmonic, clpde's exemplar, clpde's structure-texture, clpde's default (pick),
the original.
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from inpaint_texture_cases import texture_cases  # noqa: E402
from inpaint_texture_quick import biharmonic, clpde_method  # noqa: E402

COLUMNS = [
    "damaged",
    "biharmonic",
    "exemplar",
    "structure-texture",
    "default (pick)",
    "original",
]


def _rgb8(a):
    a = np.asarray(a)
    if a.dtype != np.uint8:
        a = np.clip(np.rint(a * 255), 0, 255).astype(np.uint8)
    return np.repeat(a[..., None], 3, -1) if a.ndim == 2 else a


def _row(case, pad=24, size=200):
    import cv2

    img, mask = case["image"], case["mask"]
    ys, xs = np.nonzero(mask)
    ny, nx = mask.shape
    sl = (
        slice(max(ys.min() - pad, 0), min(ys.max() + pad + 1, ny)),
        slice(max(xs.min() - pad, 0), min(xs.max() + pad + 1, nx)),
    )
    damaged = _rgb8(img).copy()
    damaged[mask] = 0
    tiles = [
        damaged,
        biharmonic(img, mask),
        clpde_method("exemplar")(img, mask),
        clpde_method("structure-texture")(img, mask),
        clpde_method(None)(img, mask),
        img,
    ]
    out = []
    for t in tiles:
        t = _rgb8(t)[sl]
        scale = size / max(t.shape[:2])
        t = cv2.resize(
            t,
            (round(t.shape[1] * scale), round(t.shape[0] * scale)),
            interpolation=cv2.INTER_NEAREST if scale >= 1 else cv2.INTER_AREA,
        )
        out.append(
            np.pad(
                t, ((0, size - t.shape[0]), (0, size + 4 - t.shape[1]), (0, 0)), constant_values=255
            )
        )
    return np.concatenate(out, 1)


def _header(width, tile=204):
    import cv2

    h = np.full((22, width, 3), 255, np.uint8)
    for i, name in enumerate(COLUMNS):
        cv2.putText(
            h, name, (i * tile + 6, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.5, (0, 0, 0), 1, cv2.LINE_AA
        )
    return h


def main(argv=None):
    import argparse

    from skimage.io import imsave

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "out",
        nargs="?",
        type=Path,
        default=Path(__file__).resolve().parents[1] / "docs" / "images",
        help="folder for the pictures (default: docs/images)",
    )
    out_dir = parser.parse_args(argv).out
    out_dir.mkdir(parents=True, exist_ok=True)
    cases = {c["name"]: c for c in texture_cases()}
    for filename, names in (
        ("inpaint_texture.png", ["brick", "grass", "fur", "tiles"]),
        ("inpaint_thick.png", ["coffee-100", "chelsea-70", "camera-60", "astronaut-80"]),
    ):
        rows = [_row(cases[n]) for n in names]
        picture = np.concatenate(
            [_header(rows[0].shape[1])]
            + [np.pad(r, ((0, 4), (0, 0), (0, 0)), constant_values=255) for r in rows]
        )
        imsave(out_dir / filename, picture, check_contrast=False)
        print(out_dir / filename)


if __name__ == "__main__":
    main()
