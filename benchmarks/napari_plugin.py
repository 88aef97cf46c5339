"""The napari plugin's responsiveness and speed, in a real (virtual-display) viewer.

- The event loop's tick rate while a long run goes on in the worker thread (target: at least
  10 ticks a second): a 50 ms QTimer during a heat flow of several seconds.
- Mask to result on the damaged astronaut (512x512, its full mask, the default method)
  through the inpaint widget, after a first run (target: under 1 s), beside the library
  call alone.

Run under a display, e.g.  xvfb-run -a python benchmarks/napari_plugin.py
Prints a table and writes benchmarks/results/napari_plugin.json.
"""

import json
import time
from pathlib import Path

import napari
import numpy as np
from qtpy.QtCore import QTimer
from qtpy.QtWidgets import QApplication

import clpde
from clpde.napari import samples, widgets


def wait(widget, app):
    while widget.worker is not None:
        app.processEvents()
        time.sleep(0.002)


def tick_rate(viewer, app, seconds=6.0):
    layer = viewer.add_image(
        np.random.default_rng(0).random((512, 512)).astype(np.float32), name="noise"
    )
    w = widgets.DenoiseWidget(viewer)
    w.image.value, w.flow.value, w.steps.value = layer, "heat", 10_000_000
    ticks = []
    timer = QTimer()
    timer.timeout.connect(lambda: ticks.append(time.perf_counter()))
    timer.start(50)
    w.run()
    start = time.perf_counter()
    while time.perf_counter() - start < seconds:
        app.processEvents()
        time.sleep(0.001)
    timer.stop()
    w.cancel()
    wait(w, app)
    gaps = np.diff(ticks)
    return {
        "seconds": seconds,
        "ticks": len(ticks),
        "ticks_per_s": len(ticks) / seconds,
        "longest_gap_ms": 1000 * float(gaps.max()) if len(gaps) else None,
    }


def astronaut(viewer, app, repeats=5):
    (damaged, dattrs, _), (mask, mattrs, _) = samples.damaged_astronaut()
    image = viewer.add_image(damaged, **dattrs)
    labels = viewer.add_labels(mask, **mattrs)
    w = widgets.InpaintWidget(viewer)
    w.image.value, w.mask.value = image, labels
    times, library = [], []
    for k in range(repeats + 1):
        start = time.perf_counter()
        w.run()
        wait(w, app)
        elapsed = time.perf_counter() - start
        start = time.perf_counter()
        clpde.inpaint(damaged, mask, channel_axis=-1)
        lib = time.perf_counter() - start
        if k:  # the first run builds the programs
            times.append(elapsed)
            library.append(lib)
    return {
        "widget_s_median": float(np.median(times)),
        "widget_s_min": float(min(times)),
        "library_s_median": float(np.median(library)),
        "repeats": repeats,
    }


def main():
    app = QApplication.instance() or QApplication([])
    viewer = napari.Viewer(show=False)
    device = clpde.get_runtime().device.name.strip()
    ticks = tick_rate(viewer, app)
    speed = astronaut(viewer, app)
    viewer.close()
    print(f"device: {device}")
    print(
        f"event loop during a run: {ticks['ticks_per_s']:.1f} ticks/s "
        f"(longest gap {ticks['longest_gap_ms']:.0f} ms; target >= 10/s)"
    )
    print(
        f"astronaut mask -> result through the widget: {speed['widget_s_median']:.3f} s "
        f"median (min {speed['widget_s_min']:.3f}); the library call alone "
        f"{speed['library_s_median']:.3f} s (target < 1 s)"
    )
    out = Path(__file__).parent / "results"
    out.mkdir(exist_ok=True)
    (out / "napari_plugin.json").write_text(
        json.dumps({"device": device, "event_loop": ticks, "astronaut": speed}, indent=1)
    )


if __name__ == "__main__":
    main()
