"""The progress policy: True always, False never, None on a terminal once the run has
lasted a few seconds (measured, not predicted from a cell count), with device loops
waiting for their queue so the bar counts work done."""

import sys
import time

import numpy as np

from clpde import _progress


def as_terminal(monkeypatch):
    """stderr, as captured, taken for a terminal (patched inside the test, once capture
    has replaced sys.stderr)."""
    monkeypatch.setattr(sys.stderr, "isatty", lambda: True)


def _slow_loop(progress, steps=8, pause=0.05):
    for _ in _progress.progress_range(progress, steps, "slow loop"):
        time.sleep(pause)


def test_default_bar_appears_after_the_delay_only(capsys, monkeypatch):
    as_terminal(monkeypatch)
    monkeypatch.setattr(_progress, "DELAY_S", 0.05)
    _slow_loop(None)
    assert "slow loop" in capsys.readouterr().err
    monkeypatch.setattr(_progress, "DELAY_S", 60.0)
    _slow_loop(None)
    assert "slow loop" not in capsys.readouterr().err


def test_true_and_false_are_kept(capsys, monkeypatch):
    as_terminal(monkeypatch)
    monkeypatch.setattr(_progress, "DELAY_S", 60.0)
    _slow_loop(True, steps=2, pause=0)
    assert "2/2" in capsys.readouterr().err
    monkeypatch.setattr(_progress, "DELAY_S", 0.0)
    _slow_loop(False, steps=2, pause=0)
    assert capsys.readouterr().err == ""


def test_default_bar_is_independent_of_the_grid_size(capsys, monkeypatch):
    as_terminal(monkeypatch)
    """A CPU run of a small surface flow that lasts longer than the delay shows its bar;
    the old rule waited for 2e9 cell updates, which a CPU takes minutes to do."""
    import clpde.surface as surface

    monkeypatch.setattr(_progress, "DELAY_S", 0.0)
    surf = surface.ImplicitSurface.sphere(1.0, spacing=0.2)
    surf.reaction_diffusion(40, progress=None)
    err = capsys.readouterr().err
    assert "reaction-diffusion" in err and "/40 [" in err


def test_device_loop_counts_steps_done(runtime):
    """With the queue, every update of the bar follows a wait for the queue: the count the
    bar shows is of finished steps."""
    import pyopencl.array as cla

    a = cla.zeros(runtime.queue, 1 << 16, np.float32)
    seen = []
    bar_range = _progress.progress_range(
        True, 30, "device loop", queue=runtime.queue, file=sys.stdout
    )
    for _ in bar_range:
        a += 1.0
        seen.append(_)
    assert seen == list(range(30)) and float(a.get()[0]) == 30.0
