"""Quickstart: damage scikit-image's astronaut photo with text and scratches, inpaint it on
the default device and write the PNGs.

    python examples/inpaint_demo.py [--out out/] [--figure docs/images/inpaint_astronaut.png]

Writes original.png, damaged.png, mask.png, inpainted.png and inpaint_before_after.png into
--out (the same as `clpde inpaint --demo -o out/`).
"""

import argparse

import numpy as np

from clpde.inpaint_demo import run_demo
from clpde.io import read_image, write_image


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--out", default="out", help="output folder (default: out/)")
    parser.add_argument("--figure", default=None, help="also write a half-size before/after PNG here")
    args = parser.parse_args()
    written = run_demo(args.out)
    for path in written:
        print(f"wrote {path}")
    if args.figure:
        pair = read_image(written[-1])
        write_image(args.figure, pair[::2, ::2].astype(np.uint8))
        print(f"wrote {args.figure}")


if __name__ == "__main__":
    main()
