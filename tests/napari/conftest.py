"""The napari tests run a real viewer on Qt's offscreen platform (qt_check sets it before Qt
loads); where napari, a Qt binding or Qt's system libraries are missing, each test module
skips with one reason that names what to install."""

import qt_check  # noqa: F401  (sets QT_QPA_PLATFORM before anything imports Qt)
