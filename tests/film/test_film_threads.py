"""The film's frame threads and OpenCV's own: one pool busy at a time, settings restored."""

from __future__ import annotations

import os
import threading
import time

import pytest

from clpde.film._motion import map_frames

cv2 = pytest.importorskip("cv2")


def test_opencv_pool_is_one_thread_inside_and_restored_after(monkeypatch):
    """map_frames sets OpenCV's pool to one thread while its frames run (they keep the cores
    busy), and sets the caller's value back after, also when several callers overlap."""
    monkeypatch.setattr(os, "cpu_count", lambda: 2)  # frames in threads on any machine
    before = cv2.getNumThreads()
    cv2.setNumThreads(3)
    try:
        seen = []

        def frame(i):
            seen.append(cv2.getNumThreads())
            time.sleep(0.02)  # the callers' frames overlap
            return i

        runs = [threading.Thread(target=map_frames, args=(frame, range(4))) for _ in range(3)]
        for run in runs:
            run.start()
        for run in runs:
            run.join()
        assert map_frames(frame, range(3)) == [0, 1, 2]
        assert set(seen) == {1} and len(seen) == 15
        assert cv2.getNumThreads() == 3
    finally:
        cv2.setNumThreads(before)
