"""What the bitwise checks (`*_bitwise.py`, bitwise_check.py) share: comparing two folders of
saved arrays byte for byte, and their `save DIR` / `compare A B` command line."""

from __future__ import annotations

import sys
from collections.abc import Callable
from pathlib import Path

import numpy as np


def same_arrays(a: Path, b: Path, width: int = 40) -> tuple[int, int]:
    """(arrays, how many differ) of a's .npy files against b's of the same name, each printed
    with its dtype, shape and whether it is bitwise equal (dtype, shape and bytes)."""
    paths = sorted(a.glob("*.npy"))
    differ = 0
    for p in paths:
        x, y = np.load(p), np.load(b / p.name)
        same = x.dtype == y.dtype and x.shape == y.shape and x.tobytes() == y.tobytes()
        differ += not same
        print(f"{p.stem:{width}s} {str(x.dtype):8s} {str(x.shape):18s} bitwise equal: {same}")
    return len(paths), differ


def compare_all(a: Path, b: Path) -> int:
    """Every array of a against b's, then one summary line; the number that differ."""
    n, differ = same_arrays(a, b)
    print(f"{n} results, {differ} differ")
    return differ


def main(save: Callable[[Path], None], doc: str, compare=compare_all) -> None:
    """`python SCRIPT save DIR` or `python SCRIPT compare A B` (exit 1 when results differ)."""
    if sys.argv[1:2] == ["save"] and len(sys.argv) >= 3:  # (a part list may follow)
        save(Path(sys.argv[2]))
    elif sys.argv[1:2] == ["compare"] and len(sys.argv) == 4:
        sys.exit(compare(Path(sys.argv[2]), Path(sys.argv[3])) > 0)
    else:
        sys.exit(doc)
