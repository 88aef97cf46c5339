"""Thesis Figure 3.14: removal of superimposed text, on scikit-image's chelsea photo.

    python examples/inpaint_fig3_14.py [--out out/]

Writes inpaint_fig3_14.png: the photo with text | the text removed.
"""

import argparse
from pathlib import Path

import numpy as np
from skimage import data

import clpde
from clpde.cli._inpaint_demo import side_by_side
from clpde.data import damage_mask
from clpde.io.images import write_image


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out", help="output folder (default: out/)")
    args = parser.parse_args()
    photo = data.chelsea()
    mask = damage_mask(photo.shape[:2], scratches=False)
    damaged = photo.copy()
    damaged[mask] = (255, 230, 40)  # yellow caption
    result, info = clpde.inpaint(damaged, mask, channel_axis=-1, return_info=True)
    psnr = 10 * np.log10(255**2 / np.mean((result[mask].astype(float) - photo[mask]) ** 2))
    Path(args.out).mkdir(parents=True, exist_ok=True)
    path = write_image(Path(args.out) / "inpaint_fig3_14.png", side_by_side(damaged, result))
    print(
        f"wrote {path}: {mask.mean():.1%} of the pixels, {info.steps} steps, "
        f"{info.seconds:.1f} s, PSNR inside the mask {psnr:.2f} dB"
    )


if __name__ == "__main__":
    main()
