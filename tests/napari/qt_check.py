"""Whether napari with Qt can run here, and if not, what to install (one reason)."""

import os

# pytest-xvfb starts a virtual X display; Qt draws there with Mesa's software OpenGL

QT_LIBRARIES = "libegl1 libgl1 libxkbcommon0 libfontconfig1 libdbus-1-3"


def _missing() -> str | None:
    try:
        import napari  # noqa: F401
        from qtpy.QtWidgets import QApplication  # noqa: F401
    except ImportError as error:
        return (f"napari with Qt is not usable here ({error}); install it with "
                f"pip install \"clpde[napari]\" and, on Debian or Ubuntu, Qt's system "
                f"libraries: apt-get install {QT_LIBRARIES}")
    return None


MISSING = _missing()
