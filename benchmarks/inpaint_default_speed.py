"""The default inpainting against its fastest peers on the quickstart's photo, warm, in one
process: the target is the default's time at most scikit-image's biharmonic fill's
on a 512x512 colour photo with a 5-10% text mask.

    python benchmarks/inpaint_default_speed.py [--repeats 5]
"""

import argparse
import time

import numpy as np

import clpde
from clpde.data import damaged_astronaut


def timed(run, repeats):
    times = []
    for _ in range(repeats):
        start = time.perf_counter()
        run()
        times.append(time.perf_counter() - start)
    return min(times), float(np.median(times))


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    args = parser.parse_args()
    import cv2
    from skimage.restoration import inpaint_biharmonic

    _, damaged, mask = damaged_astronaut()
    info = clpde.inpaint(damaged, mask, channel_axis=-1, return_info=True)[1]  # builds kernels
    print(f"astronaut 512x512x3, mask {100 * mask.mean():.1f}%, default method {info.method}")
    rows = {
        "clpde default": lambda: clpde.inpaint(damaged, mask, channel_axis=-1),
        "skimage biharmonic": lambda: inpaint_biharmonic(damaged, mask, channel_axis=-1),
        "opencv telea": lambda: cv2.inpaint(damaged, mask.astype(np.uint8), 3, cv2.INPAINT_TELEA),
    }
    print("| method | best (s) | median (s) |\n|---|---|---|")
    for name, run in rows.items():
        best, median = timed(run, args.repeats)
        print(f"| {name} | {best:.3f} | {median:.3f} |")


if __name__ == "__main__":
    main()
