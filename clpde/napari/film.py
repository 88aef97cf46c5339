"""The film widget: find the dirt and scratches of a film layer into a Labels layer the user
can correct, fill them from the neighbouring frames, and write the film back with its sound.
"""

from __future__ import annotations

from collections.abc import Callable
from pathlib import Path
from typing import Any

import napari
import numpy as np
from magicgui.widgets import ComboBox, FileEdit, PushButton, SpinBox
from napari.layers import Image, Labels

import clpde
from clpde.io.video import VideoWriter
from clpde.io.video_probe import video_info

from ._runner import RunWidget, layer_choices


def detect_film(
    frames: np.ndarray, channel_axis: int | None, grow: int, progress: Callable
) -> np.ndarray:
    """The defects of a film as labels: 1 blotch (dirt, dust), 2 line scratch."""
    mask, kinds = clpde.detect_defects(
        frames, channel_axis=channel_axis, grow=grow, return_kinds=True, progress=progress
    )
    labels = kinds.astype(np.uint8)
    labels[mask & (labels == 0)] = 1  # grown pixels count with the blotches
    return labels


def write_film(frames: np.ndarray, path: Path, source: str | None, progress: Callable) -> Path:
    """Write frames as a film; with the film they came from, keep its timing, sound and
    subtitles (through clpde's film writer)."""
    like = video_info(source) if source else None
    with VideoWriter(path, like=like, codec="ffv1" if path.suffix == ".mkv" else None) as out:
        for t, frame in enumerate(frames):
            out.write(frame)
            progress(t + 1, len(frames))
    return path


class FilmWidget(RunWidget):
    """Detect defects into a Labels layer, restore from the corrected labels, write back.

    Parameters
    ----------
    napari_viewer : napari.Viewer
        The viewer this widget serves.

    Examples
    --------
    >>> widget = FilmWidget(viewer)  # doctest: +SKIP
    >>> widget.detect()  # doctest: +SKIP
    >>> widget.run()  # doctest: +SKIP
    """

    def __init__(self, napari_viewer: napari.Viewer) -> None:
        super().__init__(napari_viewer, "clpde film")
        v = napari_viewer
        self.film = ComboBox(label="film", choices=layer_choices(v, Image))
        self.defects = ComboBox(label="defects", choices=layer_choices(v, Labels))
        self.grow = SpinBox(label="grow masks (px)", value=1, min=0, max=32)
        self.detect_button = PushButton(text="Detect defects")
        self.output = FileEdit(label="write film to", mode="w", filter="*.mp4 *.mkv *.mov *.avi")
        self.write_button = PushButton(text="Write restored film")
        self.extend([self.film, self.grow, self.detect_button, self.defects, self.output])
        self.finish_form()
        self.run_button.text = "Restore"
        self.append(self.write_button)
        self.detect_button.changed.connect(self.detect)
        self.write_button.changed.connect(self.write)

    def _frames(self) -> tuple[Image, np.ndarray, int | None]:
        layer = self.film.value
        if layer is None:
            raise clpde.InputError("choose a film layer (open an MP4, MKV or AVI file)")
        frames = np.asarray(layer.data)
        if frames.ndim != (4 if layer.rgb else 3):
            raise clpde.InputError(
                f"a film layer has frames along its first axis; this one has shape {frames.shape}"
            )
        return layer, frames, -1 if layer.rgb else None

    def detect(self) -> None:
        """Find blotches and scratches into a Labels layer the user can correct."""
        try:
            layer, frames, channel_axis = self._frames()
        except clpde.ClpdeError as error:
            self.say(str(error), error=True)
            return
        grow, name = int(self.grow.value), f"{layer.name} defects"

        def shown(labels: np.ndarray) -> None:
            self.defects.value = self.put_layer(labels, name, kind="labels")

        self.start(lambda progress: detect_film(frames, channel_axis, grow, progress), shown)

    def work(self) -> tuple[Callable, Callable]:
        layer, frames, channel_axis = self._frames()
        labels = self.defects.value
        if labels is None:
            raise clpde.InputError(
                "detect the defects first, or choose a Labels layer of the film's damage"
            )
        masks = np.asarray(labels.data) != 0
        name = f"{layer.name} restored"
        meta = dict(layer.metadata)

        def function(progress):
            return clpde.inpaint_video(frames, masks, channel_axis=channel_axis, progress=progress)

        def show(out: np.ndarray) -> Any:
            restored = self.put_layer(out, name, rgb=layer.rgb)
            restored.metadata.update(meta)

        return function, show

    def write(self) -> None:
        """Write the restored layer (or the film layer) as a film, keeping the source's
        sound when the layer came from a film file."""
        try:
            layer, frames, _ = self._frames()
        except clpde.ClpdeError as error:
            self.say(str(error), error=True)
            return
        restored = f"{layer.name} restored"
        if restored in self.viewer.layers:
            frames = np.asarray(self.viewer.layers[restored].data)
        path = Path(self.output.value)
        if path.suffix.lower() not in (".mp4", ".mkv", ".mov", ".avi"):
            self.say("choose a film file to write (.mp4, .mkv, .mov or .avi)", error=True)
            return
        source = layer.metadata.get("clpde_film")
        self.start(
            lambda progress: write_film(frames, path, source, progress),
            lambda written: self.say(f"wrote {written}"),
        )
