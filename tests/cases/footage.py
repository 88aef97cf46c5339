"""Real footage for the film tests: frames of opencv-doc's vtest.avi (walking people)."""

from __future__ import annotations

from pathlib import Path

import numpy as np

VTEST = Path("/usr/share/doc/opencv-doc/examples/data/vtest.avi")


def people(count: int = 8, start: int = 60) -> np.ndarray:
    """Frames of vtest.avi around walking people, downscaled to 192x144 and cropped."""
    import cv2

    cap = cv2.VideoCapture(str(VTEST))
    for _ in range(start):
        cap.grab()
    frames = []
    for _ in range(count):
        ok, f = cap.read()
        assert ok
        f = cv2.resize(f, (192, 144), interpolation=cv2.INTER_AREA)
        frames.append(cv2.cvtColor(f, cv2.COLOR_BGR2RGB)[40:136, 16:176])
    cap.release()
    return np.stack(frames)
