"""Every widget in a headless viewer: a run on sample data, through the worker thread and
into a layer, gives the library call's array."""

import numpy as np
import pytest
from qt_check import MISSING, WAIT_MS, run_and_wait

if MISSING is not None:
    pytest.skip(MISSING, allow_module_level=True)

import clpde  # noqa: E402
from clpde.napari import samples, widgets  # noqa: E402


def crop_astronaut(viewer, size=128):
    (damaged, dattrs, _), (mask, mattrs, _) = samples.damaged_astronaut()
    image = viewer.add_image(damaged[:size, :size], **dattrs)
    labels = viewer.add_labels(mask[:size, :size], **mattrs)
    return image, labels


def test_inpaint_widget_gives_the_library_result(viewer, qtbot):
    image, labels = crop_astronaut(viewer)
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value = image, labels
    run_and_wait(qtbot, w)
    out = viewer.layers["damaged astronaut inpainted"].data
    expected = clpde.inpaint(image.data, labels.data != 0, channel_axis=-1)
    np.testing.assert_array_equal(out, expected)
    assert out.dtype == np.uint8


def test_inpaint_widget_grows_the_mask_and_takes_shapes_and_soft_masks(viewer, qtbot):
    image, _ = crop_astronaut(viewer, 96)
    shapes = viewer.add_shapes(
        [np.array([[20, 20], [20, 40], [40, 40], [40, 20]])], shape_type="polygon", name="box"
    )
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value, w.grow.value = image, shapes, 2
    run_and_wait(qtbot, w)
    mask = clpde.grow_mask(np.asarray(shapes.to_labels(labels_shape=(96, 96))) != 0, 2)
    expected = clpde.inpaint(image.data, mask, channel_axis=-1)
    np.testing.assert_array_equal(viewer.layers[-1].data, expected)
    soft = np.zeros((96, 96), np.float32)
    soft[30:40, 30:40] = 0.7
    soft_layer = viewer.add_image(soft, name="soft")
    w.mask.value, w.grow.value = soft_layer, 0
    run_and_wait(qtbot, w)
    expected = clpde.inpaint(image.data, soft, channel_axis=-1)
    np.testing.assert_array_equal(viewer.layers["damaged astronaut inpainted"].data, expected)


def test_inpaint_widget_grows_a_stacks_mask_plane_by_plane(viewer, qtbot):
    stack = np.random.default_rng(2).random((3, 40, 40)).astype(np.float32)
    marks = np.zeros((3, 40, 40), np.uint8)
    marks[1, 15:20, 10:30] = 1
    image, labels = viewer.add_image(stack, name="stack"), viewer.add_labels(marks, name="m")
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value, w.grow.value = image, labels, 2
    run_and_wait(qtbot, w)
    expected = stack.copy()
    expected[1] = clpde.inpaint(stack[1], clpde.grow_mask(marks[1] != 0, 2))
    np.testing.assert_array_equal(viewer.layers["stack inpainted"].data, expected)


def test_inpaint_on_paint_reruns_the_stroke_box(viewer, qtbot):
    image, labels = crop_astronaut(viewer, 128)
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value = image, labels
    run_and_wait(qtbot, w)
    w.live.value = True
    before = viewer.layers["damaged astronaut inpainted"].data.copy()
    # a stroke where nothing was painted yet
    free = np.argwhere(~np.asarray(labels.data[8:-8, 8:-8] != 0))[::97] + 8
    y, x = next((y, x) for y, x in free if not labels.data[y - 4 : y + 5, x - 4 : x + 5].any())
    labels.brush_size = 5
    labels.paint((y, x), 1)
    assert w.worker is not None  # the stroke started a run at once
    qtbot.waitUntil(lambda: w.worker is None, timeout=WAIT_MS)
    after = viewer.layers["damaged astronaut inpainted"].data
    changed = np.argwhere(np.any(after != before, axis=-1))
    assert len(changed) > 0
    reach = 2 + 24 + 1  # the brush's radius and the stroke box's margin
    assert np.all(np.abs(changed - (y, x)) <= reach)


def test_denoise_widget_tv_and_flows(viewer, qtbot):
    rng = np.random.default_rng(0)
    clean = np.zeros((64, 64), np.float32)
    clean[16:48, 16:48] = 1.0
    noisy = (clean + rng.normal(0, 0.1, clean.shape)).astype(np.float32)
    layer = viewer.add_image(noisy, name="noisy")
    w = widgets.DenoiseWidget(viewer)
    w.image.value = layer
    assert "estimated noise" in w.noise.value
    w.flow.value, w.weight.value = "tv-denoise", 0.1
    run_and_wait(qtbot, w)
    np.testing.assert_array_equal(
        viewer.layers["noisy tv-denoise"].data, clpde.denoise_tv(noisy, weight=0.1)
    )
    w.flow.value, w.steps.value = "perona-malik", 30
    run_and_wait(qtbot, w)
    np.testing.assert_array_equal(
        viewer.layers["noisy perona-malik"].data, clpde.diffuse(noisy, "perona-malik", steps=30)
    )


def test_denoise_preview_runs_on_the_slice_in_view(viewer, qtbot):
    stack = np.random.default_rng(1).random((3, 40, 40)).astype(np.float32)
    layer = viewer.add_image(stack, name="stack")
    viewer.dims.set_current_step(0, 2)
    w = widgets.DenoiseWidget(viewer)
    w.image.value, w.flow.value, w.steps.value, w.preview.value = layer, "heat", 10, True
    run_and_wait(qtbot, w)
    np.testing.assert_array_equal(
        viewer.layers["stack heat preview"].data, clpde.diffuse(stack[2], "heat", steps=10)
    )


def test_track_widget_carries_two_labels_both_ways(viewer, qtbot):
    (frames, fattrs, _), _ = samples.tracking_sequence(frames=8, size=64)
    truth = np.zeros(frames.shape, np.int32)
    y, x = np.mgrid[:64, :64]
    for t in range(8):
        truth[t][(y - 20) ** 2 + (x - 18 - t) ** 2 < 64] = 1
        truth[t][(y - 46) ** 2 + (x - 46 + t) ** 2 < 49] = 2
    frames = np.where(truth > 0, 0.8, frames).astype(np.float32)
    image = viewer.add_image(frames, **fattrs)
    seeds = np.zeros_like(truth)
    seeds[4] = truth[4]
    labels = viewer.add_labels(seeds, name="objects")
    viewer.dims.set_current_step(0, 4)
    w = widgets.TrackWidget(viewer)
    w.image.value, w.labels.value = image, labels
    run_and_wait(qtbot, w)
    out = viewer.layers["objects tracked"].data
    expected, confidence = widgets.propagate_labels(frames, truth[4], 4, "both", lambda *_: None)
    np.testing.assert_array_equal(out, expected)
    for label in (1, 2):
        for t in range(8):
            inter = np.sum((out[t] == label) & (truth[t] == label))
            union = np.sum((out[t] == label) | (truth[t] == label))
            assert inter / union > 0.7, (label, t)
    assert "confidence min" in w.confidence.value


def test_surface_widget_values_on_the_users_mesh(viewer, qtbot):
    (((vertices, faces, values), attrs, _),) = samples.torus()
    layer = viewer.add_surface((vertices, faces, values), **attrs)
    w = widgets.SurfaceWidget(viewer)
    w.surface.value, w.flow.value, w.amount.value, w.resolution.value = layer, "heat", 0.02, 40
    run_and_wait(qtbot, w)
    out = viewer.layers["torus heat"].data
    assert out[0].shape == vertices.shape and out[2].shape == (len(vertices),)
    expected = widgets.run_surface_flow(vertices, faces, values, "heat", 0.02, 40, lambda *_: None)
    np.testing.assert_allclose(out[2], expected, rtol=0, atol=1e-6)
    # the heat flow smooths: the noise's spread shrinks
    assert np.std(out[2] - vertices[:, 0]) < np.std(values - vertices[:, 0])


def test_samples_load_into_a_viewer(viewer):
    for make in (samples.damaged_astronaut, samples.tracking_sequence, samples.torus):
        for data, attrs, kind in make():
            getattr(viewer, f"add_{kind}")(data, **attrs)
    assert len(viewer.layers) == 5


def test_bad_input_is_one_message_and_no_run(viewer, qtbot):
    w = widgets.InpaintWidget(viewer)
    w.run()
    assert w.worker is None and "choose an image layer" in w.status.value
