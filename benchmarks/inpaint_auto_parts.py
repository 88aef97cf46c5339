"""method="auto" on masks that mix thin strokes with thick holes in one box.

    PYTHONPATH=<checkout> python benchmarks/inpaint_auto_parts.py [--repeat 3]

Cases: clpde.data.damaged_astronaut() (a caption, a date and scratches: bold strokes,
6-8 px thick in places, all in one box), and each photo of inpaint_quality.PHOTOS with the
text mask and the blobs (20-30 px) together (one box). For each: PSNR in the mask, PSNR on
the blobs and on the rest, what auto picked (info.box_methods, and the pixels the exemplar
filled), and the median CPU and wall time of `repeat` runs after a warm-up. Run it with
the old and the new code, alternating, for same-run ratios.
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
import inpaint_quality as q  # noqa: E402


def cases():
    from skimage import data

    import clpde.data

    original, _, mask = clpde.data.damaged_astronaut()
    yield "damaged_astronaut", original, mask, np.zeros_like(mask)
    for name in q.PHOTOS:
        image = getattr(data, name)()
        blobs = q.blob_mask(image.shape[:2])
        yield f"{name} text+blobs", image, q.text_mask(image.shape[:2]) | blobs, blobs


def main(argv=None):
    import clpde

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--method", default="auto")
    args = ap.parse_args(argv)
    print(f"# clpde from {Path(clpde.__file__).parent}, method={args.method}")
    print("| case | PSNR mask | blobs | rest | picked | exemplar px | CPU s | wall s |")
    print("|---|---|---|---|---|---|---|---|")
    for name, image, mask, blobs in cases():
        damaged = image.copy()
        damaged[mask] = 255
        axis = -1 if image.ndim == 3 else None

        def run(damaged=damaged, mask=mask, axis=axis):
            return clpde.inpaint(damaged, mask, channel_axis=axis, progress=False, seed=0,
                                 method=args.method, return_info=True)
        run()
        times = []
        for _ in range(args.repeat):
            t0, c0 = time.perf_counter(), time.process_time()
            out, info = run()
            times.append((time.process_time() - c0, time.perf_counter() - t0))
        cpu, wall = np.median(times, axis=0)
        psnr = [q.psnr_in_mask(out, image, m) if m.any() else float("nan")
                for m in (mask, blobs, mask & ~blobs)]
        picked = ", ".join(info.box_methods)
        px = sum(getattr(info, "box_exemplar_pixels", []) or [0])
        print(f"| {name} | {psnr[0]:.2f} | {psnr[1]:.2f} | {psnr[2]:.2f} | {picked} | {px} | "
              f"{cpu:.3f} | {wall:.3f} |", flush=True)


if __name__ == "__main__":
    main()
