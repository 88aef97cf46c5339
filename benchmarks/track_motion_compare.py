"""How well and how fast the object's motion is found on the fast class of
benchmarks/track_photo_corpus.py (10-26 px a frame, both halves): clpde.tracking.appearance's
object_motion (masked correlation + affine Lucas-Kanade, what motion='image' uses), the
median of clpde.motion.optical_flow over the object, and the median of OpenCV's DIS flow
(medium preset) over it. Error: distance between the predicted and the true centre of the
object in the next frame (object_motion is given the true mask of the first frame of the
pair); time: ms per frame pair (median), in turns in one process.

    python benchmarks/track_motion_compare.py
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import numpy as np
from scipy import ndimage

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))
sys.path.insert(0, str(ROOT / "benchmarks"))

from track_photo_corpus import MAKERS  # noqa: E402


def main():
    import cv2

    from clpde.motion import optical_flow
    from clpde.tracking.appearance import object_motion
    from clpde.tracking.inputs import scaled_frames

    dis = cv2.DISOpticalFlow_create(cv2.DISOPTICAL_FLOW_PRESET_MEDIUM)
    errors = {"object_motion": [], "clpde flow": [], "DIS": []}
    times = {k: [] for k in errors}
    for seed in range(4):
        frames, masks = MAKERS["fast"](seed)
        looks = scaled_frames(list(frames), True)
        grey = frames @ np.array([0.299, 0.587, 0.114])
        u8 = (grey * 255).astype(np.uint8)
        for k in range(len(frames) - 1):
            c0 = np.array(ndimage.center_of_mass(masks[k]))
            c1 = np.array(ndimage.center_of_mass(masks[k + 1]))
            t = time.perf_counter()
            a = object_motion(looks[k], looks[k + 1], masks[k])
            times["object_motion"].append(time.perf_counter() - t)
            centre = np.linalg.solve(a[:, :2], c0 - a[:, 2])
            errors["object_motion"].append(np.hypot(*(centre - c1)))
            for name in ("clpde flow", "DIS"):
                t = time.perf_counter()
                if name == "DIS":
                    flow = dis.calc(u8[k], u8[k + 1], None)
                else:
                    flow = optical_flow(grey[k], grey[k + 1], warps=3, iterations=15)
                times[name].append(time.perf_counter() - t)
                d = np.array([np.median(flow[masks[k]][:, 1]), np.median(flow[masks[k]][:, 0])])
                errors[name].append(np.hypot(*(c0 + d - c1)))
    for name in errors:
        e = np.array(errors[name])
        print(
            f"{name:14s} error px median {np.median(e):.2f}, max {e.max():.2f}, "
            f"> 3 px in {(e > 3).mean():.0%}; {1000 * np.median(times[name]):.1f} ms a pair"
        )


if __name__ == "__main__":
    main()
