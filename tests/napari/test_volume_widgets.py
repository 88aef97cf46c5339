"""The widgets' "whole volume (3D)" choice: a 3-D layer runs through the library's 3-D calls,
with the layer's scale as the voxel spacing, and gives their arrays."""

import numpy as np
import pytest
from qt_check import MISSING, run_and_wait

if MISSING is not None:
    pytest.skip(MISSING, allow_module_level=True)

import clpde  # noqa: E402
from clpde.napari import widgets  # noqa: E402
from clpde.volumes import inpaint_volume  # noqa: E402

SPACING = (2.0, 1.0, 1.0)


def noisy_ball(shape=(8, 24, 24)):
    z, y, x = np.indices(shape)
    clean = ((2 * (z - 4)) ** 2 + (y - 12) ** 2 + (x - 12) ** 2 < 64).astype(np.float32)
    rng = np.random.default_rng(3)
    return (clean + rng.normal(0, 0.1, shape)).astype(np.float32)


def test_denoise_widget_runs_the_whole_volume_with_the_layers_scale(viewer, qtbot):
    noisy = noisy_ball()
    layer = viewer.add_image(noisy, name="ball", scale=SPACING)
    w = widgets.DenoiseWidget(viewer)
    w.image.value, w.volume.value = layer, True
    w.flow.value, w.weight.value = "tv-denoise", 0.1
    run_and_wait(qtbot, w)
    out = viewer.layers["ball tv-denoise 3D"]
    expected = clpde.denoise_tv(noisy, weight=0.1, spacing=SPACING)
    np.testing.assert_array_equal(out.data, expected)
    np.testing.assert_array_equal(out.scale, SPACING)
    # the spacing matters: the same volume on a unit grid is another result
    assert not np.array_equal(expected, clpde.denoise_tv(noisy, weight=0.1, spacing=(1, 1, 1)))
    w.flow.value, w.steps.value = "perona-malik", 20
    run_and_wait(qtbot, w)
    np.testing.assert_array_equal(
        viewer.layers["ball perona-malik 3D"].data,
        clpde.diffuse(noisy, "perona-malik", steps=20, spacing=SPACING),
    )


def test_inpaint_widget_fills_a_volume_from_3d_labels(viewer, qtbot):
    volume = noisy_ball()
    mask = np.zeros(volume.shape, np.uint8)
    mask[3:5, 8:14, 10:16] = 1
    image = viewer.add_image(volume, name="ball", scale=SPACING)
    labels = viewer.add_labels(mask, name="holes", scale=SPACING)
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value, w.volume.value = image, labels, True
    run_and_wait(qtbot, w)
    out = viewer.layers["ball inpainted"].data
    expected = inpaint_volume(volume, mask != 0, spacing=SPACING)
    np.testing.assert_array_equal(out, expected)
    assert not np.array_equal(out, volume)


def test_whole_volume_on_a_2d_or_rgb_layer_is_one_message(viewer):
    flat = viewer.add_image(np.zeros((16, 16), np.float32), name="flat")
    w = widgets.DenoiseWidget(viewer)
    w.image.value, w.volume.value = flat, True
    w.run()
    assert w.worker is None and "3-D grey layer" in w.status.value
    colour = viewer.add_image(np.zeros((4, 16, 16, 3), np.uint8), name="colour", rgb=True)
    w.image.value = colour
    w.run()
    assert w.worker is None and "untick it" in w.status.value
