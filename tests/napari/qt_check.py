"""Whether napari with Qt can run here, and if not, what to install (one reason).

pytest-xvfb starts a virtual X display before collection; Qt draws there with Mesa's
software OpenGL (Qt's offscreen platform has no OpenGL, which napari's canvas needs). Qt
aborts the whole process when its platform cannot start, so that is tried in a child first.
"""

import subprocess
import sys

NEEDS = (
    'pip install "clpde[napari]" and, on Debian or Ubuntu, apt-get install xvfb '
    "libgl1-mesa-dri libegl1 libxkbcommon-x11-0 libxcb-icccm4 libxcb-image0 "
    "libxcb-keysyms1 libxcb-randr0 libxcb-render-util0 libxcb-xinerama0 libxcb-shape0 "
    "libxcb-cursor0 libfontconfig1 libdbus-1-3"
)

PROBE = "from qtpy.QtWidgets import QApplication; QApplication([])"


def _missing() -> str | None:
    try:
        import napari  # noqa: F401
        import pytest_xvfb  # noqa: F401
        import pytestqt  # noqa: F401
    except ImportError as error:
        return f"napari's tests need napari, pytest-qt and pytest-xvfb ({error}): {NEEDS}"
    try:
        started = subprocess.run(
            [sys.executable, "-c", PROBE], capture_output=True, text=True, timeout=60
        )
    except subprocess.TimeoutExpired:
        return f"Qt did not start within 60 s: {NEEDS}"
    if started.returncode != 0:
        last = (started.stderr.strip().splitlines() or ["no message"])[-1]
        return f"Qt cannot start here ({last}): {NEEDS}"
    return None


MISSING = _missing()


WAIT_MS = 240_000  # a widget's run on the CPU under load, with room to spare


def run_and_wait(qtbot, widget):
    """Start a widget's run and wait for its worker thread to finish."""
    widget.run()
    assert widget.worker is not None, widget.status.value
    qtbot.waitUntil(lambda: widget.worker is None, timeout=WAIT_MS)
