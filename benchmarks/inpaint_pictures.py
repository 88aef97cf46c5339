"""The pictures of docs/inpainting.md: oblique structure, thick holes, soft masks (the
transport), and every installed method on four kinds of damage.

    python benchmarks/inpaint_pictures.py [OUTDIR]   (default docs/images)
"""

from __future__ import annotations

import sys
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from inpaint_quality import (  # noqa: E402
    psnr_in_mask,
    run_biharmonic,
    run_clpde,
    thick_mask,
)

from tests.cases.inpaint_slots import rings_case, stripes_case  # noqa: E402


def _rgb(image):
    return np.repeat(image[..., None], 3, -1) if image.ndim == 2 else image


def _damaged(image, mask):
    out = _rgb(image).copy()
    out[mask] = (255, 0, 255)
    return out


def _label(panel, text):
    import cv2

    out = np.ascontiguousarray(panel.copy())
    cv2.rectangle(out, (0, 0), (out.shape[1], 22), (255, 255, 255), -1)
    cv2.putText(out, text, (4, 16), cv2.FONT_HERSHEY_SIMPLEX, 0.45, (0, 0, 0), 1, cv2.LINE_AA)
    return out


def _grid(rows, gap=4):
    h = max(p.shape[0] for row in rows for p in row)
    lines = []
    for row in rows:
        parts = []
        for p in row:
            parts += [np.pad(p, ((0, h - p.shape[0]), (0, gap), (0, 0)), constant_values=255)]
        lines.append(np.concatenate(parts, 1))
    w = max(line.shape[1] for line in lines)
    lines = [
        np.pad(line, ((0, gap), (0, w - line.shape[1]), (0, 0)), constant_values=255)
        for line in lines
    ]
    return np.concatenate(lines, 0)


def _zoom(image, box, factor):
    y0, y1, x0, x1 = box
    crop = _rgb(image)[y0:y1, x0:x1]
    return np.kron(crop, np.ones((factor, factor, 1), np.uint8))


def oblique(path):
    rows = []
    for name, (image, mask) in (
        ("stripes 30", stripes_case(30)),
        ("stripes 45", stripes_case(45)),
        ("rings", rings_case()),
    ):
        if name == "rings":
            box = (40, 88, 20, 108)
        else:
            box = (40, 88, 24, 104)
        results = [
            ("damaged", image, None),
            ("biharmonic", run_biharmonic(image, mask), True),
            (
                "central (thesis)",
                run_clpde(image, mask, method="transport", stencil="central"),
                True,
            ),
            ("isotropic (default)", run_clpde(image, mask, method="transport"), True),
        ]
        row = []
        for label, out, score in results:
            shown = _damaged(out, mask) if score is None else out
            text = label if score is None else f"{label} {psnr_in_mask(out, image, mask):.1f} dB"
            row.append(_label(_zoom(shown, box, 3), text))
        rows.append(row)
    write(path, _grid(rows))


def thick(path):
    from skimage import data

    image = data.coffee()
    mask = thick_mask(image.shape[:2], 100)
    ys, xs = np.nonzero(mask)
    box = (max(0, ys.min() - 40), ys.max() + 40, max(0, xs.min() - 40), xs.max() + 40)
    # the transport's multiresolution (docs/inpainting.md): its levels and coarse starts
    results = [
        ("damaged", _damaged(image, mask)),
        ("1 level", run_clpde(image, mask, method="transport", levels=1)),
        (
            "4 levels, upsampled start",
            run_clpde(image, mask, method="transport", levels=4, coarse_start="upsampled"),
        ),
        ("2 levels, corrected (automatic)", run_clpde(image, mask, method="transport")),
    ]
    row = []
    for label, out in results:
        text = label if label == "damaged" else f"{label} {psnr_in_mask(out, image, mask):.1f} dB"
        row.append(_label(_zoom(out, box, 2), text))
    write(path, _grid([row[:2], row[2:]]))


def soft(path):
    from skimage import data

    truth = data.astronaut()[30:230, 140:340]
    ny, nx = truth.shape[:2]
    y, x = np.mgrid[0:ny, 0:nx]
    # a translucent stain: opaque in its middle, fading out
    damage = np.clip(1.6 - np.hypot((y - 90) / 45, (x - 100) / 70) * 1.6, 0, 1)
    damage = np.where(damage > 0.02, damage, 0.0)
    stain = np.array([230, 200, 120], float)
    observed = np.round((1 - damage[..., None]) * truth + damage[..., None] * stain).astype(
        np.uint8
    )
    hard = run_clpde(observed, damage > 0)
    soft = run_clpde(observed, damage)
    region = damage > 0
    row = [
        _label(observed, "stained (damage 0..1)"),
        _label(hard, f"hard mask {psnr_in_mask(hard, truth, region):.1f} dB"),
        _label(soft, f"soft mask {psnr_in_mask(soft, truth, region):.1f} dB"),
        _label(truth, "original"),
    ]
    write(path, _grid([row]))


def methods_figure(path):
    """Before and after for every installed method, on one case of each kind of damage."""
    from inpaint_quality import blob_mask, text_mask
    from scipy import ndimage
    from skimage import data

    from clpde.inpainting.registry import available

    def around(mask, size, which=0):
        """A size x size box centred on the which-th component of the mask."""
        labels, _ = ndimage.label(mask)
        cy, cx = (int(v) for v in ndimage.center_of_mass(labels == which + 1))
        y0 = int(np.clip(cy - size // 2, 0, mask.shape[0] - size))
        x0 = int(np.clip(cx - size // 2, 0, mask.shape[1] - size))
        return y0, y0 + size, x0, x0 + size

    camera, chelsea, coffee = data.camera(), data.chelsea(), data.coffee()
    stripes, slot = stripes_case(30)
    blobs, hole = blob_mask(chelsea.shape[:2]), thick_mask(coffee.shape[:2], 100)
    cases = [
        ("text", camera, text_mask(camera.shape), (150, 278, 170, 298), 2),
        ("blobs", chelsea, blobs, around(blobs, 128, 1), 2),
        ("stripes 30", stripes, slot, (32, 96, 32, 96), 4),
        ("thick hole", coffee, hole, around(hole, 256), 1),
    ]
    rows = []
    for name, image, mask, box, factor in cases:
        row = [_label(_zoom(_damaged(image, mask), box, factor), name)]
        for method in available():
            out = run_clpde(image, mask, method=method)
            row.append(
                _label(_zoom(out, box, factor), f"{method} {psnr_in_mask(out, image, mask):.1f} dB")
            )
        row.append(_label(_zoom(image, box, factor), "original"))
        rows.append(row)
    write(path, _grid(rows))


def write(path, image):
    import imageio.v3 as iio

    path.parent.mkdir(parents=True, exist_ok=True)
    iio.imwrite(path, image)
    print(f"wrote {path}", file=sys.stderr)


if __name__ == "__main__":
    import argparse

    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument(
        "out",
        nargs="?",
        type=Path,
        default=Path(__file__).resolve().parents[1] / "docs" / "images",
        help="folder for the pictures (default: docs/images)",
    )
    out = parser.parse_args().out
    oblique(out / "inpaint_oblique.png")
    thick(out / "inpaint_thick_levels.png")
    soft(out / "inpaint_soft.png")
    methods_figure(out / "inpaint_methods.png")
