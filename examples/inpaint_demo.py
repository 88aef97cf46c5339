"""Quickstart: damage scikit-image's astronaut photo with text and scratches, inpaint it on
the default device and write the PNGs.

    python examples/inpaint_demo.py [--out out] [--docs]

Writes original.png, damaged.png, mask.png, inpainted.png and inpaint_before_after.png into
the folder out/inpaint_demo, exactly as `clpde inpaint --demo -o out` does (the same code:
a rerun of either replaces the demo's own files); --docs also writes the README's half-size
before/after picture.
"""

import argparse
from pathlib import Path

import numpy as np

from clpde.cli._inpaint_demo import run_demo
from clpde.errors import InputError
from clpde.io.images import read_image, write_image

FIGURE = Path(__file__).resolve().parent.parent / "docs" / "images" / "inpaint_astronaut.png"


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument(
        "--out",
        type=Path,
        default=Path("out"),
        help="the folder in which the demo's folder inpaint_demo is written (default: out)",
    )
    parser.add_argument(
        "--docs", action="store_true", help=f"also write the README's picture {FIGURE}"
    )
    args = parser.parse_args()
    try:
        written = run_demo(args.out)
    except InputError as exc:  # one line, as the command line says it
        raise SystemExit(f"inpaint_demo: error: {exc}") from None
    for path in written:
        print(f"wrote {path}")
    if args.docs:
        pair = read_image(written[-1])
        write_image(FIGURE, pair[::2, ::2].astype(np.uint8))
        print(f"wrote {FIGURE}")


if __name__ == "__main__":
    main()
