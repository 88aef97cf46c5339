"""The viewer stays responsive during a run, Cancel leaves nothing behind, a missing OpenCL
driver is one clear message, the manifest validates and the readers read."""

import os
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import numpy as np
import pytest
from qt_check import MISSING

if MISSING is not None:
    pytest.skip(MISSING, allow_module_level=True)

from qtpy.QtCore import QThreadPool, QTimer  # noqa: E402

from clpde.napari import readers, widgets  # noqa: E402

REPO = Path(__file__).resolve().parents[2]


def long_diffusion(viewer, steps=400_000):
    """A denoise widget set up for a run of several seconds on any device."""
    layer = viewer.add_image(
        np.random.default_rng(0).random((128, 128)).astype(np.float32), name="noise"
    )
    w = widgets.DenoiseWidget(viewer)
    w.image.value, w.flow.value, w.steps.value = layer, "heat", steps
    return w


def test_event_loop_ticks_during_a_long_run(viewer, qtbot):
    w = long_diffusion(viewer)
    ticks = []
    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(50)
    w.run()
    qtbot.wait(3000)
    timer.stop()
    running = w.worker is not None
    w.cancel()
    qtbot.waitUntil(lambda: w.worker is None, timeout=60_000)
    assert running, "the run should still be going after 3 s"
    assert len(ticks) >= 5  # the loop kept turning while the run went on


def test_cancel_leaves_no_layer_and_no_worker(viewer, qtbot):
    w = long_diffusion(viewer)
    before = [layer.name for layer in viewer.layers]
    w.run()
    qtbot.wait(500)
    w.cancel()
    qtbot.waitUntil(lambda: w.worker is None, timeout=60_000)
    assert [layer.name for layer in viewer.layers] == before
    assert w.status.value == "cancelled"
    assert QThreadPool.globalInstance().waitForDone(10_000)
    assert QThreadPool.globalInstance().activeThreadCount() == 0
    assert w.run_button.enabled and not w.cancel_button.enabled


def test_no_opencl_driver_is_one_message_with_the_fix(tmp_path):
    """In a process that finds no OpenCL platform at all, a run says how to get one."""
    script = textwrap.dedent("""
        import numpy as np, napari
        from clpde.napari import widgets
        viewer = napari.Viewer(show=False)
        viewer.add_image(np.zeros((16, 16), np.float32), name="a")
        w = widgets.DenoiseWidget(viewer)
        w.flow.value = "heat"
        w.run()
        from qtpy.QtCore import QThreadPool
        from qtpy.QtWidgets import QApplication
        for _ in range(200):
            QApplication.processEvents()
            if w.worker is None:
                break
            QThreadPool.globalInstance().waitForDone(50)
        print("STATUS:", w.status.value)
    """)
    # a vendors path that does not exist: the OpenCL loader then finds no platform at all
    env = dict(os.environ, OCL_ICD_VENDORS=str(tmp_path / "no-vendors"), PYTHONPATH=str(REPO))
    env.pop("CLPDE_DEVICE", None)
    done = subprocess.run(
        [sys.executable, "-c", script], env=env, capture_output=True, text=True, timeout=300
    )
    status = [line for line in done.stdout.splitlines() if line.startswith("STATUS:")]
    assert status, done.stderr[-2000:]
    assert "OpenCL" in status[0] and "pip install" in status[0], status[0]


def test_manifest_validates_with_imports():
    from npe2 import PluginManifest

    manifest = PluginManifest.from_file(REPO / "clpde" / "napari" / "napari.yaml")
    manifest.validate_imports()
    assert {w.display_name for w in manifest.contributions.widgets} >= {
        "Inpaint",
        "Denoise and diffuse",
        "Track",
        "Film restoration",
        "Surface flows",
    }


def test_mesh_reader_keeps_the_mesh(tmp_path):
    import trimesh

    mesh = trimesh.creation.icosphere(subdivisions=2)
    path = tmp_path / "ball.ply"
    mesh.export(path)
    reader = readers.get_mesh_reader(str(path))
    assert reader is not None and readers.get_mesh_reader(str(tmp_path / "a.png")) is None
    ((data, attrs, kind),) = reader(str(path))
    assert kind == "surface" and len(data[0]) == len(mesh.vertices)
    np.testing.assert_array_equal(data[1], mesh.faces)


def test_film_reader_gives_frames_and_the_source(tmp_path):
    pytest.importorskip("av")
    from clpde.io.video import write_video

    frames = np.zeros((5, 32, 48, 3), np.uint8)
    for t in range(5):
        frames[t, :, 8 * t : 8 * t + 8] = 200
    path = write_video(tmp_path / "clip.mp4", frames, 10)
    ((data, attrs, kind),) = readers.get_film_reader(str(path))(str(path))
    assert kind == "image" and data.shape == frames.shape
    assert attrs["metadata"]["clpde_film"] == str(path)
    assert np.abs(data.astype(int) - frames).mean() < 6  # H.264's loss only
