"""Runs of clpde in a worker thread, with napari's progress bar and a cancel button.

Every widget of the plugin is a `RunWidget`: a form of magicgui widgets, a Run and a Cancel
button and a status line. `RunWidget.start` runs a library call in a worker thread; the call
gets a `progress=` callable that moves napari's progress bar (through a Qt signal, so the
bar is touched on the GUI thread only) and raises `Cancelled` once Cancel was pressed, which
is how clpde's library functions let a caller stop a run. The result reaches the viewer on
the GUI thread, through the worker's ``returned`` signal; a cancelled run adds nothing.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any

import napari
import numpy as np
from magicgui.widgets import ComboBox, Container, Label, PushButton
from napari.qt.threading import create_worker
from napari.utils import progress as napari_progress
from napari.utils.notifications import show_error, show_info
from qtpy.QtCore import QObject, Signal

import clpde
from clpde.runtime import NoDeviceError


class Cancelled(Exception):
    """Raised inside a run by its progress callable once the user pressed Cancel."""


class _Relay(QObject):
    # Emitted from the worker thread; Qt queues it to the GUI thread, where the bar lives.
    moved = Signal(float, float)


def device_choices(_widget: Any = None) -> list[tuple[str, int | None]]:
    """The Device dropdown: "automatic" and every device of `clpde.devices()`."""
    choices: list[tuple[str, int | None]] = [("automatic", None)]
    try:
        for info in clpde.devices():
            choices.append((f"{info.index}: {info.name} ({info.type})", info.index))
    except clpde.ClpdeError:
        pass  # no OpenCL at all: the first run says so, with the fix
    return choices


def layer_choices(viewer: napari.Viewer, *kinds: type) -> Callable[[Any], list]:
    """A ComboBox's choices: the viewer's layers of the given kinds, as (name, layer)."""
    return lambda _widget=None: [
        (layer.name, layer) for layer in viewer.layers if isinstance(layer, kinds)
    ]


class RunWidget(Container):
    """A form, Run and Cancel buttons and a status line; runs in a worker thread.

    Parameters
    ----------
    viewer : napari.Viewer
        The viewer whose layers the form lists and where results go.
    title : str
        The run's name on napari's progress bar.
    """

    def __init__(self, viewer: napari.Viewer, title: str) -> None:
        super().__init__()
        self.viewer, self.title = viewer, title
        self.device = ComboBox(label="device", choices=device_choices)
        self.run_button = PushButton(text="Run")
        self.cancel_button = PushButton(text="Cancel", enabled=False)
        self.status = Label(value="")
        self.run_button.changed.connect(self.run)
        self.cancel_button.changed.connect(self.cancel)
        self.worker = None
        self._cancel = threading.Event()
        self._relay = _Relay()
        self._relay.moved.connect(self._moved)
        self._bar = None
        for event in (viewer.layers.events.inserted, viewer.layers.events.removed):
            event.connect(lambda _event: self.reset_choices())

    def finish_form(self) -> None:
        """Append the shared controls after a subclass's own."""
        self.extend([self.device, self.run_button, self.cancel_button, self.status])

    # ---- running ------------------------------------------------------------------------
    def run(self) -> None:
        """Start this widget's work: its `work()` (every widget defines one) reads the form
        and returns (a function of a progress callable, a callback for its result)."""
        try:
            job = self.work()
        except (clpde.ClpdeError, ValueError) as error:
            self.say(str(error), error=True)
            return
        if job is not None:
            self.start(*job)

    def start(self, function: Callable, on_result: Callable) -> None:
        """Run ``function(progress)`` in a worker thread; ``on_result(result)`` gets its
        result on the GUI thread unless the run was cancelled or failed."""
        if self.worker is not None:
            self.say("a run is already going on; cancel it first")
            return
        if self.device.value is not None:
            try:
                clpde.use_device(self.device.value)
            except clpde.ClpdeError as error:
                self.say(str(error), error=True)
                return
        self._cancel.clear()
        self._bar = napari_progress(total=0, desc=self.title)

        def progress(done, total):
            if self._cancel.is_set():
                raise Cancelled
            self._relay.moved.emit(float(done or 0), float(total or 0))

        # errors are ours to report (_failed); napari would re-raise them in the event loop
        worker = create_worker(function, progress, _ignore_errors=True)
        worker.returned.connect(on_result)
        worker.errored.connect(self._failed)
        worker.finished.connect(self._finished)
        self.worker = worker
        self.run_button.enabled, self.cancel_button.enabled = False, True
        self.say(f"{self.title}...")
        worker.start()

    def cancel(self) -> None:
        """Ask the run to stop at its next progress report."""
        if self.worker is not None:
            self._cancel.set()
            self.say("cancelling...")

    def _moved(self, done: float, total: float) -> None:
        if self._bar is not None:
            if total and self._bar.total != int(total):
                self._bar.total = int(total)
            self._bar.n = int(done)
            self._bar.refresh()

    def _failed(self, error: Exception) -> None:
        if isinstance(error, Cancelled):
            self.say("cancelled")
        elif isinstance(error, NoDeviceError):
            self.say(str(error), error=True)
        else:
            self.say(f"{type(error).__name__}: {error}", error=True)

    def _finished(self) -> None:
        if self._bar is not None:
            self._bar.close()
            self._bar = None
        self.worker = None
        self.run_button.enabled, self.cancel_button.enabled = True, False
        if self.status.value.endswith("..."):
            self.say("done")

    def say(self, message: str, error: bool = False) -> None:
        """Show a message in the status line, and as a notification when it is an error."""
        self.status.value = message
        if error:
            show_error(f"clpde: {message}")
        elif message not in ("done", "") and not message.endswith("..."):
            show_info(f"clpde: {message}")

    def put_layer(
        self, data: np.ndarray, name: str, kind: str = "image", **options: Any
    ) -> napari.layers.Layer:
        """Replace the data of the layer called `name`, or add one of `kind`."""
        if name in self.viewer.layers:
            layer = self.viewer.layers[name]
            layer.data = data
            return layer
        add = getattr(self.viewer, f"add_{kind}")
        return add(data, name=name, **options)


def current_index(viewer: napari.Viewer, axis: int = 0) -> int:
    """The slider's position along `axis` (the frame or slice the user is looking at)."""
    return int(viewer.dims.current_step[axis])
