"""Thesis Figure 3.15: the progressive nature of the algorithm. Intermediate states of the
inpainting of scikit-image's coffee photo, damaged with text and scratches.

    python examples/inpaint_fig3_15.py [--out out/]

Writes inpaint_fig3_15.png (damaged, the start inside the region, then states after 136,
680 steps and the end) and inpaint_fig3_15.gif (the whole evolution).
"""

import argparse
from pathlib import Path

import numpy as np
from skimage import data

import clpde
from clpde.cli._inpaint_demo import side_by_side
from clpde.data import damage_mask
from clpde.io.images import write_gif, write_image


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out", help="output folder (default: out/)")
    args = parser.parse_args()
    photo = data.coffee()[60:316, 130:450]
    mask = damage_mask(photo.shape[:2], seed=11)
    damaged = photo.copy()
    damaged[mask] = 255
    _, states = clpde.inpaint(damaged, mask, channel_axis=-1, snapshots=68, tol=0, mean_tol=0)
    chosen = [s for s in states if s.step in (0, 136, 680)] + [states[-1]]
    for s in chosen:
        mse = np.mean((s.image[mask].astype(float) - photo[mask]) ** 2)
        print(f"step {s.step:4d}: PSNR inside the mask {10 * np.log10(255**2 / mse):.2f} dB")
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    panel = side_by_side(damaged, *(s.image for s in chosen))
    print(f"wrote {write_image(out / 'inpaint_fig3_15.png', panel)}")
    frames = [damaged] + [s.image for s in states]
    print(f"wrote {write_gif(out / 'inpaint_fig3_15.gif', [f[::2, ::2] for f in frames])}")


if __name__ == "__main__":
    main()
