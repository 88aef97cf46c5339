"""Quickstart: damage scikit-image's astronaut photo with text and scratches, inpaint it on
the default device and write the PNGs.

    python examples/inpaint_demo.py [--out out/inpaint_demo] [--docs]

Writes original.png, damaged.png, mask.png, inpainted.png and inpaint_before_after.png into
the folder --out, replacing it (as `clpde inpaint --demo -o out/inpaint_demo --overwrite`);
--docs also writes the README's half-size before/after picture.
"""

import argparse
from pathlib import Path

import numpy as np

from clpde.cli._inpaint_demo import run_demo
from clpde.io.images import read_image, write_image

FIGURE = Path(__file__).resolve().parent.parent / "docs" / "images" / "inpaint_astronaut.png"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("out") / "inpaint_demo",
        help="output folder, replaced by each run (default: out/inpaint_demo)",
    )
    parser.add_argument(
        "--docs", action="store_true", help=f"also write the README's picture {FIGURE}"
    )
    args = parser.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    written = run_demo(args.out, overwrite=True)
    for path in written:
        print(f"wrote {path}")
    if args.docs:
        pair = read_image(written[-1])
        write_image(FIGURE, pair[::2, ::2].astype(np.uint8))
        print(f"wrote {FIGURE}")


if __name__ == "__main__":
    main()
