"""Thesis Figure 3.10: the influence of the interleaved diffusion. From left to right: the
damaged image, the result with no diffusion (B = 0), with the default amount (B = 2 steps
every A = 15 transport steps) and with too much (B = 15).

    python examples/inpaint_fig3_10.py [--out out/]
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
    photo = data.camera()[40:232, 170:362]  # the photographer's head and camera
    mask = damage_mask(photo.shape, seed=5, text=False) | damage_mask(
        photo.shape, seed=8, text=False
    )
    damaged = np.where(mask, 255, photo).astype(np.uint8)
    panels = [damaged]
    for b in (0, 2, 15):
        result = clpde.inpaint(damaged, mask, diffusion_steps=b)
        psnr = 10 * np.log10(255**2 / np.mean((result[mask].astype(float) - photo[mask]) ** 2))
        print(f"B = {b:2d}: PSNR inside the mask {psnr:.2f} dB")
        panels.append(result)
    Path(args.out).mkdir(parents=True, exist_ok=True)
    path = write_image(Path(args.out) / "inpaint_fig3_10.png", side_by_side(*panels))
    print(f"wrote {path}")


if __name__ == "__main__":
    main()
