"""Screenshots of each napari widget after a run on the sample data.

    python examples/napari_screenshots.py [--out out/napari_screenshots] [--docs]

Needs clpde[napari] and a display (a virtual one will do: `xvfb-run -a python ...`).
--docs writes them into docs/images/napari/ instead, for docs/napari.md and the README.
"""

import argparse
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[1]
DOCS = ROOT / "docs" / "images" / "napari"
OUT = ROOT / "out" / "napari_screenshots"  # set by main()


def finish(widget, app):
    while widget.worker is not None:
        app.processEvents()
        time.sleep(0.01)
    for _ in range(20):
        app.processEvents()


def shoot(viewer, app, name, angles=None):
    viewer.window._qt_window.resize(1500, 820)
    viewer.reset_view()
    if angles is not None:
        viewer.camera.angles = angles
        viewer.camera.zoom *= 0.55  # reset_view frames the grid's flat extent, not the turn
    for _ in range(20):
        app.processEvents()
    OUT.mkdir(parents=True, exist_ok=True)
    viewer.screenshot(str(OUT / f"{name}.png"), canvas_only=False, flash=False)
    print("wrote", OUT / f"{name}.png")


def add(viewer, layer_data):
    return [getattr(viewer, f"add_{kind}")(data, **attrs) for data, attrs, kind in layer_data]


def inpaint(app):
    viewer = napari.Viewer(title="clpde: inpaint")
    image, labels = add(viewer, samples.damaged_astronaut())
    w = widgets.InpaintWidget(viewer)
    viewer.window.add_dock_widget(w, name="clpde inpaint")
    w.image.value, w.mask.value = image, labels
    w.run()
    finish(w, app)
    labels.visible = False
    viewer.grid.enabled = True  # the damaged photo beside the result
    shoot(viewer, app, "inpaint")
    viewer.close()


def denoise(app):
    viewer = napari.Viewer(title="clpde: denoise")
    rng = np.random.default_rng(0)
    photo, _, _ = samples.clpde.data.damaged_astronaut()
    grey = photo[20:276, 100:356].mean(axis=2).astype(np.float32) / 255
    noisy = np.clip(grey + rng.normal(0, 0.08, grey.shape), 0, 1).astype(np.float32)
    layer = viewer.add_image(noisy, name="noisy")
    w = widgets.DenoiseWidget(viewer)
    viewer.window.add_dock_widget(w, name="clpde denoise")
    w.image.value, w.flow.value = layer, "tv-denoise"
    w.run()
    finish(w, app)
    viewer.grid.enabled = True
    shoot(viewer, app, "denoise")
    viewer.close()


def track(app):
    viewer = napari.Viewer(title="clpde: track")
    image, labels = add(viewer, samples.tracking_sequence())
    w = widgets.TrackWidget(viewer)
    viewer.window.add_dock_widget(w, name="clpde track")
    w.image.value, w.labels.value = image, labels
    viewer.dims.set_current_step(0, 0)  # the object is drawn on the first frame
    w.run()
    finish(w, app)
    labels.visible = False
    viewer.dims.set_current_step(0, 12)
    shoot(viewer, app, "track")
    viewer.close()


def surface(app):
    viewer = napari.Viewer(title="clpde: surface flows", ndisplay=3)
    (layer,) = add(viewer, samples.torus())
    w = widgets.SurfaceWidget(viewer)
    viewer.window.add_dock_widget(w, name="clpde surface")
    w.surface.value, w.flow.value, w.amount.value, w.resolution.value = layer, "heat", 0.05, 64
    w.run()
    finish(w, app)
    viewer.grid.enabled = True  # the noisy values beside the smoothed ones
    shoot(viewer, app, "surface")
    viewer.close()


def film(app):
    """A short dusty pan (made here), its detected defects and the restored frames."""
    import tempfile

    import av

    from clpde.data import damaged_astronaut
    from clpde.napari.film import FilmWidget
    from clpde.napari.readers import read_film

    photo = damaged_astronaut()[0][100:260, 140:380]
    rng = np.random.default_rng(0)
    frames = np.stack([np.roll(photo, 3 * t, axis=1)[:, :200] for t in range(10)])
    for t in range(10):  # dark dirt and bright dust, new on every frame
        for _ in range(6):
            y, x, r = rng.integers(8, 150), rng.integers(8, 190), rng.integers(2, 5)
            frames[t, y - r : y + r, x - r : x + r] = 10 if rng.random() < 0.5 else 245
    path = Path(tempfile.mkdtemp()) / "dusty.mp4"
    with av.open(str(path), "w") as out:
        stream = out.add_stream("libx264", rate=10)
        stream.width, stream.height, stream.pix_fmt = 200, 160, "yuv420p"
        stream.options = {"crf": "0"}
        for frame in frames:
            out.mux(stream.encode(av.VideoFrame.from_ndarray(frame, format="rgb24")))
        out.mux(stream.encode())
    viewer = napari.Viewer(title="clpde: film restoration")
    ((data, attrs, _),) = read_film(str(path))
    layer = viewer.add_image(data, **attrs)
    w = FilmWidget(viewer)
    viewer.window.add_dock_widget(w, name="clpde film")
    w.film.value = layer
    w.detect()
    finish(w, app)
    w.run()
    finish(w, app)
    viewer.layers["dusty"].visible = True
    viewer.grid.enabled = True
    viewer.dims.set_current_step(0, 5)
    shoot(viewer, app, "film")
    viewer.close()


def main(argv=None) -> None:
    global OUT, napari, samples, widgets
    parser = argparse.ArgumentParser(description="Screenshots of clpde's napari widgets.")
    parser.add_argument(
        "--out", type=Path, default=OUT, help="output folder (default: out/napari_screenshots)"
    )
    parser.add_argument(
        "--docs", action="store_true", help=f"write into {DOCS.relative_to(ROOT)} instead"
    )
    args = parser.parse_args(argv)
    OUT = DOCS if args.docs else args.out
    import napari as napari_module
    from qtpy.QtWidgets import QApplication

    from clpde.napari import samples as samples_module
    from clpde.napari import widgets as widgets_module

    napari, samples, widgets = napari_module, samples_module, widgets_module
    app = QApplication.instance() or QApplication([])
    for make in (inpaint, denoise, track, surface, film):
        make(app)


if __name__ == "__main__":
    main()
