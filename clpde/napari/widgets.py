"""The plugin's dock widgets: inpaint, denoise and diffuse, track, film, surfaces.

Each widget is a `RunWidget`: its `work` reads the form on the GUI thread and returns the
library call to run in a worker thread and what to do with its result. The library calls
are clpde's public functions, so a widget's result is the library's result.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

import napari
import numpy as np
from magicgui.widgets import CheckBox, ComboBox, FloatSpinBox, Label, SpinBox
from napari.layers import Image, Labels, Shapes, Surface

import clpde
from clpde.inpainting.registry import available as available_methods
from clpde.planar.rof import estimate_sigma
from clpde.volumes import inpaint_volume

from ._runner import RunWidget, current_index, layer_choices

# ---- masks from layers -------------------------------------------------------------------


def mask_from_layer(layer: napari.layers.Layer, shape: tuple[int, ...]) -> np.ndarray:
    """The inpainting mask a layer means, of the image's spatial `shape`.

    Labels: nonzero labels. Shapes: the shapes' interiors. Image: bool or integer data is
    nonzero where to fill; float data is a soft mask (the degree of damage in [0, 1]).
    """
    if isinstance(layer, Labels):
        mask = np.asarray(layer.data) != 0
    elif isinstance(layer, Shapes):
        mask = np.asarray(layer.to_labels(labels_shape=shape)) != 0
    elif isinstance(layer, Image):
        data = np.asarray(layer.data)
        mask = np.clip(data, 0.0, 1.0) if data.dtype.kind == "f" else data != 0
    else:
        raise clpde.InputError(
            f"a mask comes from a Labels, Shapes or Image layer, not {type(layer).__name__}"
        )
    if mask.shape != tuple(shape):
        raise clpde.InputError(
            f"the mask layer has shape {mask.shape} but the image's "
            f"pixels are {tuple(shape)}; paint the mask on a layer of the "
            "image's size"
        )
    return mask


def volume_spacing(layer: Image) -> tuple[float, float, float]:
    """The (z, y, x) voxel size of a 3-D grey layer (its napari ``scale``), or one line
    saying why the layer is no volume."""
    if layer.rgb or np.ndim(layer.data) != 3:
        raise clpde.InputError(
            f"'whole volume (3D)' runs on a 3-D grey layer (Z, Y, X); {layer.name!r} has shape "
            f"{np.shape(layer.data)}{' (rgb)' if layer.rgb else ''}: untick it for this layer"
        )
    return tuple(float(h) for h in layer.scale[-3:])


def _spatial(layer: Image) -> tuple[tuple[int, ...], int | None]:
    """An image layer's pixel shape (without colour) and channel axis."""
    data = layer.data
    if layer.rgb:
        return tuple(data.shape[:-1]), -1
    return tuple(data.shape), None


# ---- inpaint -----------------------------------------------------------------------------


def inpaint_planes(
    image: np.ndarray,
    mask: np.ndarray,
    channel_axis: int | None,
    progress: Callable,
    **options: Any,
) -> np.ndarray:
    """`clpde.inpaint` of a 2-D image, or of each plane of a stack (2-D + t or z) that has
    damage, with one progress figure over all planes."""
    spatial = mask.shape
    if len(spatial) == 2:
        return clpde.inpaint(image, mask, channel_axis=channel_axis, progress=progress, **options)
    out = np.array(image, copy=True)
    planes = [i for i in range(spatial[0]) if np.any(mask[i])]
    for k, i in enumerate(planes):
        out[i] = inpaint_planes(
            image[i], mask[i], channel_axis, lambda *_, k=k: progress(k, len(planes)), **options
        )
        progress(k + 1, len(planes))
    return out


def grow_planes(mask: np.ndarray, px: int) -> np.ndarray:
    """`clpde.grow_mask` of a 2-D mask, or of each plane of a stack's (a stack's planes are
    inpainted one by one, so each grows in its own plane)."""
    if mask.ndim == 2:
        return clpde.grow_mask(mask, px)
    return np.stack([grow_planes(plane, px) for plane in mask])


class InpaintWidget(RunWidget):
    """Fill the damage painted on a Labels, Shapes or (soft) Image layer.

    Parameters
    ----------
    napari_viewer : napari.Viewer
        The viewer this widget serves.

    Examples
    --------
    >>> widget = InpaintWidget(viewer)  # doctest: +SKIP
    >>> widget.image.value, widget.mask.value = photo_layer, mask_layer  # doctest: +SKIP
    >>> widget.run()  # doctest: +SKIP
    """

    def __init__(self, napari_viewer: napari.Viewer) -> None:
        super().__init__(napari_viewer, "clpde inpaint")
        v = napari_viewer
        self.image = ComboBox(label="image", choices=layer_choices(v, Image))
        self.mask = ComboBox(label="mask", choices=layer_choices(v, Labels, Shapes, Image))
        self.method = ComboBox(label="method", choices=["default", *available_methods()])
        self.grow = SpinBox(label="grow mask (px)", value=0, min=0, max=64)
        self.live = CheckBox(label="inpaint on paint", value=False)
        self.volume = CheckBox(label="whole volume (3D)", value=False)
        self.extend([self.image, self.mask, self.method, self.grow, self.live, self.volume])
        self.finish_form()
        self.live.changed.connect(self._watch)
        self.mask.changed.connect(self._watch)
        self._watched = None
        self._painted_mask = None

    def _inputs(self) -> tuple[Image, np.ndarray, np.ndarray, int | None]:
        layer, mask_layer = self.image.value, self.mask.value
        if layer is None or mask_layer is None:
            raise clpde.InputError(
                "choose an image layer and a mask layer (paint the damage on a Labels layer)"
            )
        shape, channel_axis = _spatial(layer)
        mask = mask_from_layer(mask_layer, shape)
        if self.grow.value:
            mask = grow_planes(mask, int(self.grow.value))
        return layer, np.asarray(layer.data), mask, channel_axis

    def _method(self) -> str | None:
        return None if self.method.value == "default" else self.method.value

    def work(self) -> tuple[Callable, Callable]:
        if self.volume.value:
            return self._volume_work()
        layer, image, mask, channel_axis = self._inputs()
        method = self._method()
        name = f"{layer.name} inpainted"

        def function(progress):
            return inpaint_planes(image, mask, channel_axis, progress, method=method)

        return function, lambda out: self.put_layer(out, name, rgb=layer.rgb)

    def _volume_work(self) -> tuple[Callable, Callable]:
        """`clpde.volumes.inpaint_volume` of the whole 3-D layer, the mask a 3-D Labels
        layer, the spacing the layer's scale."""
        layer, mask_layer = self.image.value, self.mask.value
        if layer is None or not isinstance(mask_layer, Labels):
            raise clpde.InputError(
                "a whole volume is filled from a 3-D Labels layer: choose the image and "
                "a Labels layer painted on it"
            )
        spacing = volume_spacing(layer)
        mask = mask_from_layer(mask_layer, np.shape(layer.data))
        if self.grow.value or self._method() is not None:
            raise clpde.InputError(
                "a whole volume is filled by the biharmonic fill without growing the mask: "
                "set the method to 'default' and grow to 0"
            )
        image, name = np.asarray(layer.data), f"{layer.name} inpainted"

        def function(progress):
            # progress(done, total) over the missing voxels, box by box; cancel raises in it
            return inpaint_volume(image, mask, spacing=spacing, progress=progress)

        return function, lambda out: self.put_layer(out, name, scale=layer.scale)

    # ---- inpaint on paint: re-run on the painted stroke's box only ----------------------
    def _watch(self, *_args: Any) -> None:
        # labels_update, not paint: napari emits paint before it writes the stroke
        if self._watched is not None:
            self._watched.events.labels_update.disconnect(self._painted)
            self._watched = None
        layer = self.mask.value
        if self.live.value and isinstance(layer, Labels):
            layer.events.labels_update.connect(self._painted)
            self._watched = layer
            self._painted_mask = np.asarray(layer.data) != 0

    def _painted(self, _event: Any = None) -> None:
        if self.worker is not None or self.image.value is None:
            return
        layer, image, mask, channel_axis = self._inputs()
        before = self._painted_mask
        self._painted_mask = np.asarray(self.mask.value.data) != 0
        name = f"{layer.name} inpainted"
        changed = np.argwhere(before != self._painted_mask) if before is not None else []
        if len(changed) == 0:
            return
        if name not in self.viewer.layers or mask.ndim != 2:
            self.run()  # the first result (or a stack) is made whole
            return
        # the stroke's box, grown so the methods see the surroundings they read
        margin = 24 + int(self.grow.value)
        lo = np.maximum(changed.min(axis=0) - margin, 0)
        hi = np.minimum(changed.max(axis=0) + margin + 1, mask.shape)
        box = tuple(slice(a, b) for a, b in zip(lo, hi, strict=True))
        method = self._method()
        result = self.viewer.layers[name]

        def function(progress):
            return clpde.inpaint(
                image[box], mask[box], channel_axis=channel_axis, method=method, progress=progress
            )

        def paste(out):
            data = np.array(result.data, copy=True)
            data[box] = out
            result.data = data

        self.start(function, paste)


# ---- denoise and diffuse -----------------------------------------------------------------


class DenoiseWidget(RunWidget):
    """TV denoising (by noise level or weight) and the planar diffusion flows, with a
    preview on the slice in view.

    Parameters
    ----------
    napari_viewer : napari.Viewer
        The viewer this widget serves.

    Examples
    --------
    >>> widget = DenoiseWidget(viewer)  # doctest: +SKIP
    >>> widget.flow.value = "tv-denoise"  # doctest: +SKIP
    >>> widget.run()  # doctest: +SKIP
    """

    def __init__(self, napari_viewer: napari.Viewer) -> None:
        super().__init__(napari_viewer, "clpde denoise")
        v = napari_viewer
        self.image = ComboBox(label="image", choices=layer_choices(v, Image))
        self.flow = ComboBox(label="flow", choices=["tv-denoise", *clpde.FLOWS])
        self.sigma = FloatSpinBox(
            label="noise sigma (0: estimate)", value=0.0, min=0.0, max=1e6, step=0.5
        )
        self.weight = FloatSpinBox(
            label="TV weight (0: from sigma)", value=0.0, min=0.0, max=1e6, step=0.01
        )
        self.steps = SpinBox(label="flow steps", value=100, min=1, max=10_000_000)
        self.preview = CheckBox(label="preview the slice in view only", value=False)
        self.volume = CheckBox(label="whole volume (3D)", value=False)
        self.noise = Label(value="")
        self.extend(
            [self.image, self.flow, self.sigma, self.weight, self.steps]
            + [self.preview, self.volume, self.noise]
        )
        self.finish_form()
        self.image.changed.connect(self._show_noise)
        self._show_noise()

    def _show_noise(self, *_args: Any) -> None:
        layer = self.image.value
        if layer is None:
            self.noise.value = ""
            return
        image, channel_axis = self._plane(layer, preview=True)
        sigma = estimate_sigma(image, channel_axis=channel_axis)
        self.noise.value = f"estimated noise sigma: {np.round(sigma, 3)}"

    def _plane(self, layer: Image, preview: bool) -> tuple[np.ndarray, int | None]:
        """The data to run on: the whole 2-D image, or the slice in view of a stack."""
        data = np.asarray(layer.data)
        channel_axis = -1 if layer.rgb else None
        spatial = data.ndim - (1 if layer.rgb else 0)
        if spatial > 2 and preview:
            data = data[current_index(self.viewer)]
        return data, channel_axis

    def work(self) -> tuple[Callable, Callable]:
        layer = self.image.value
        if layer is None:
            raise clpde.InputError("choose an image layer")
        data, channel_axis = self._plane(layer, self.preview.value)
        flow, steps = self.flow.value, int(self.steps.value)
        sigma = self.sigma.value or None
        weight = self.weight.value or None
        # a volume's spacing sends the library calls down their 3-D path
        spacing = volume_spacing(layer) if self.volume.value else None
        if spacing is not None and self.preview.value:
            raise clpde.InputError("untick either 'preview' or 'whole volume (3D)'")

        def one(plane, progress):
            if flow == "tv-denoise":
                return clpde.denoise_tv(
                    plane,
                    sigma=sigma,
                    weight=weight,
                    channel_axis=channel_axis,
                    spacing=spacing,
                    progress=progress,
                )
            return clpde.diffuse(
                plane,
                flow,
                steps=steps,
                channel_axis=channel_axis,
                spacing=spacing,
                progress=progress,
            )

        def function(progress):
            if spacing is not None or data.ndim - (channel_axis is not None) == 2:
                return one(data, progress)
            return np.stack(
                [one(plane, lambda *_, k=k: progress(k, len(data))) for k, plane in enumerate(data)]
            )

        name = f"{layer.name} {flow}" + (" preview" if self.preview.value else "")
        name += " 3D" if spacing is not None else ""
        scale = layer.scale if spacing is not None else None
        return function, lambda out: self.put_layer(out, name, rgb=layer.rgb, scale=scale)


# ---- tracking ----------------------------------------------------------------------------


class TrackWidget(RunWidget):
    """Carry labels from the slice or frame in view through Z or T, each label its own
    object, with clpde's morphing active contours.

    Parameters
    ----------
    napari_viewer : napari.Viewer
        The viewer this widget serves.

    Examples
    --------
    >>> widget = TrackWidget(viewer)  # doctest: +SKIP
    >>> widget.run()  # doctest: +SKIP
    """

    def __init__(self, napari_viewer: napari.Viewer) -> None:
        super().__init__(napari_viewer, "clpde track")
        v = napari_viewer
        self.image = ComboBox(label="frames or slices", choices=layer_choices(v, Image))
        self.labels = ComboBox(label="labels", choices=layer_choices(v, Labels))
        self.direction = ComboBox(label="direction", choices=["both", "forwards", "backwards"])
        self.threshold = FloatSpinBox(
            label="flag confidence below", value=0.5, min=0.0, max=1.0, step=0.05
        )
        self.confidence = Label(value="")
        self.extend([self.image, self.labels, self.direction, self.threshold, self.confidence])
        self.finish_form()

    def work(self) -> tuple[Callable, Callable]:
        layer, labels_layer = self.image.value, self.labels.value
        if layer is None or labels_layer is None:
            raise clpde.InputError(
                "choose a stack (2-D + t or a z-stack) and a Labels layer "
                "with the objects drawn on the slice in view"
            )
        frames = np.asarray(layer.data)
        if layer.rgb:
            frames = frames.mean(axis=-1)
        labels = np.asarray(labels_layer.data)
        if frames.ndim != 3 or labels.shape != frames.shape:
            raise clpde.InputError(
                f"tracking needs a 3-D stack and a Labels layer of its "
                f"shape; got {frames.shape} and {labels.shape}"
            )
        start = current_index(self.viewer)
        seeds = labels[start]
        ids = [int(i) for i in np.unique(seeds) if i != 0]
        if not ids:
            raise clpde.InputError(
                f"no label drawn on slice {start}; draw the objects on the slice in view, then run"
            )
        direction = self.direction.value
        name = f"{labels_layer.name} tracked"
        result = propagate_labels
        return (
            lambda progress: result(frames, seeds, start, direction, progress),
            lambda out: self._show(out, name),
        )

    def _show(self, out: tuple[np.ndarray, np.ndarray], name: str) -> None:
        tracked, confidence = out
        self.put_layer(tracked, name, kind="labels")
        low = np.flatnonzero(confidence < self.threshold.value)
        listed = ", ".join(str(i) for i in low[:20]) + (" ..." if len(low) > 20 else "")
        self.confidence.value = (
            f"confidence min {confidence.min():.2f}; below "
            f"{self.threshold.value:g}: {listed or 'none'}"
        )


def propagate_labels(
    frames: np.ndarray, seeds: np.ndarray, start: int, direction: str, progress: Callable
) -> tuple[np.ndarray, np.ndarray]:
    """Track each label of ``seeds`` (the labels on slice `start`) through `frames`.

    Returns the tracked labels (same shape as frames) and the per-frame confidence (the
    lowest over the labels; 1 on frames no run reached).
    """
    ids = [int(i) for i in np.unique(seeds) if i != 0]
    out = np.zeros(frames.shape, np.int32)
    confidence = np.ones(len(frames))
    runs = []
    if direction in ("both", "forwards"):
        runs.append(np.arange(start, len(frames)))
    if direction in ("both", "backwards"):
        runs.append(np.arange(start, -1, -1))
    total = sum(len(r) for r in runs) * len(ids)
    done = 0
    for label in ids:
        for order in runs:
            if len(order) < 2:
                out[start][seeds == label] = label
                continue
            masks, score = clpde.track(
                frames[order],
                seeds == label,
                return_confidence=True,
                progress=lambda d, _t, base=done: progress(base + d, total),
            )
            done += len(order)
            for index, mask in zip(order, masks, strict=True):
                out[index][mask & (out[index] == 0)] = label
            confidence[order] = np.minimum(confidence[order], score)
    return out, confidence


# ---- surfaces ----------------------------------------------------------------------------

SURFACE_FLOWS = ("heat", "tv", "reaction-diffusion")


def run_surface_flow(
    vertices: np.ndarray,
    faces: np.ndarray,
    values: np.ndarray,
    flow: str,
    amount: float,
    resolution: int,
    progress: Callable,
) -> np.ndarray:
    """A surface flow on the implicit surface of a mesh, read back at the mesh's vertices.

    `amount` is the flow's time (heat, tv) or its iterations (reaction-diffusion). Returns
    one value per vertex.
    """
    import trimesh

    mesh = trimesh.Trimesh(vertices=vertices, faces=faces, process=False)
    surf = clpde.surface.ImplicitSurface.from_mesh(mesh, resolution=resolution)
    if flow == "reaction-diffusion":
        chemicals = surf.reaction_diffusion(int(amount), progress=progress)
        u = chemicals[1]
    else:
        u0 = surf.field_from_mesh(values)
        u = getattr(surf, flow)(u0, float(amount), progress=progress)
    return surf.sample(u, vertices)


class SurfaceWidget(RunWidget):
    """Run a surface flow (heat, TV, reaction-diffusion) and show the values as vertex
    colours on the user's own mesh.

    Parameters
    ----------
    napari_viewer : napari.Viewer
        The viewer this widget serves.

    Examples
    --------
    >>> widget = SurfaceWidget(viewer)  # doctest: +SKIP
    >>> widget.run()  # doctest: +SKIP
    """

    def __init__(self, napari_viewer: napari.Viewer) -> None:
        super().__init__(napari_viewer, "clpde surface")
        v = napari_viewer
        self.surface = ComboBox(label="surface", choices=layer_choices(v, Surface))
        self.flow = ComboBox(label="flow", choices=list(SURFACE_FLOWS))
        self.amount = FloatSpinBox(
            label="time (iterations for reaction-diffusion)",
            value=0.05,
            min=0.0,
            max=1e6,
            step=0.01,
        )
        self.resolution = SpinBox(label="grid resolution", value=64, min=16, max=512)
        self.extend([self.surface, self.flow, self.amount, self.resolution])
        self.finish_form()
        self.flow.changed.connect(self._default_amount)

    def _default_amount(self, flow: str) -> None:
        self.amount.value = 2000.0 if flow == "reaction-diffusion" else 0.05

    def work(self) -> tuple[Callable, Callable]:
        layer = self.surface.value
        if layer is None:
            raise clpde.InputError(
                "choose a Surface layer (open a mesh file, or File > Open Sample > clpde > torus)"
            )
        vertices, faces = np.asarray(layer.data[0]), np.asarray(layer.data[1])
        values = (
            np.asarray(layer.data[2], np.float64)
            if len(layer.data) > 2
            else np.zeros(len(vertices))
        )
        if values.ndim != 1:
            values = values.reshape(-1, len(vertices))[-1]  # the last time point
        flow, amount, resolution = self.flow.value, self.amount.value, self.resolution.value
        name = f"{layer.name} {flow}"

        def function(progress):
            return run_surface_flow(vertices, faces, values, flow, amount, resolution, progress)

        return function, lambda out: self.put_layer(
            (vertices, faces, out), name, kind="surface", colormap="viridis"
        )
