"""The defaults on every OpenCL CPU runtime present, side by side in one run: PoCL and, where
it is registered, Intel's oneAPI CPU runtime (pip install intel-opencl-rt intel-cmplr-lib-rt;
register its libintelocl.so in an ICD folder named by OCL_ICD_VENDORS, see
docs/portability.md).

    OCL_ICD_VENDORS=/path/to/vendors python benchmarks/runtimes.py [--repeats 3]

Each row: the default call, warm (kernels built by a first call), best of `repeats`, and
the largest difference between the runtimes' results. Inputs: the damaged astronaut
(clpde.data), scikit-image's camera with noise, a disc moving over noise (timing only: the
tracking's accuracy is benchmarks/track_corpus.py's), a noisy clip with blotches, a sphere.
"""

from __future__ import annotations

import argparse
import functools
import time

import numpy as np

import clpde
from clpde.data import damaged_astronaut


def timed(run, repeats):
    out = run()  # builds the kernels
    best = np.inf
    for _ in range(repeats):
        t0 = time.perf_counter()
        out = run()
        best = min(best, time.perf_counter() - t0)
    return best, out


def workloads():
    from skimage import data

    from clpde.surface import ImplicitSurface

    rng = np.random.default_rng(0)
    _, damaged, mask = damaged_astronaut()
    camera = data.camera().astype(np.float32) / 255
    noisy = np.clip(camera + rng.normal(0, 0.08, camera.shape), 0, 1).astype(np.float32)
    yy, xx = np.mgrid[:192, :192]
    frames = np.stack(
        [((yy - 96) ** 2 + (xx - 70 - 3 * k) ** 2 < 900) * 0.6 + 0.2 for k in range(8)]
    ).astype(np.float32)
    frames = np.clip(frames + rng.normal(0, 0.05, frames.shape), 0, 1).astype(np.float32)
    clip = np.repeat(camera[None, ::2, ::2], 6, 0).copy()
    clip += rng.normal(0, 0.02, clip.shape).astype(np.float32)
    clip[2, 100:108, 120:130] = 1.0  # a blotch
    clip[4, 40:46, 30:38] = 0.0
    n = 64
    ax = np.arange(n) - (n - 1) / 2
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = np.sqrt(x**2 + y**2 + z**2) - 20

    def restore(device):
        masks = clpde.detect_defects(clip, device=device)
        return clpde.inpaint_video(clip, masks, device=device)

    def surface(device):
        return ImplicitSurface(phi, 1.0, device=device).heat(z / n, 2.0)

    return {
        "inpaint (astronaut 512x512x3, spectral)": lambda d: clpde.inpaint(
            damaged, mask, channel_axis=-1, device=d
        ),
        "denoise_tv (camera 512x512)": lambda d: clpde.denoise_tv(noisy, device=d),
        "track (8 frames 192x192)": lambda d: clpde.track(frames, frames[0] > 0.5, device=d),
        "restore (detect + fill, 6 frames 256x256)": restore,
        "surface heat (sphere, 64^3)": surface,
    }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=3)
    args = parser.parse_args()
    cpus = [d for d in clpde.devices() if d.type == "cpu"]
    for d in clpde.devices():
        print(d.describe())
    print()
    names = [d.platform for d in cpus]
    print("| default call | " + " | ".join(f"{n} (s)" for n in names) + " | max difference |")
    print("|---" * (len(names) + 2) + "|")
    for label, run in workloads().items():
        times, outs = [], []
        for d in cpus:
            t, out = timed(functools.partial(run, d.index), args.repeats)
            times.append(t)
            outs.append(np.asarray(out, np.float64))
        diff = max(float(np.abs(o - outs[0]).max()) for o in outs)
        cells = " | ".join(f"{t:.3f}" for t in times)
        print(f"| {label} | {cells} | {diff:.2g} |", flush=True)


if __name__ == "__main__":
    main()
