"""The napari tests' viewer (pytest-qt's and napari's fixtures; the modules skip where
napari cannot run, qt_check.MISSING)."""

import pytest


@pytest.fixture
def viewer(make_napari_viewer):
    return make_napari_viewer()
