"""Results of the inpainting methods, contour tracking and region tracking in bricks, saved
for a bitwise check across the package's re-rooming (the other *_bitwise.py scripts cover the
transport, the flows, the surfaces and, in film_bitwise.py, the film path).

    PYTHONPATH=<old tree> python benchmarks/layout_bitwise.py save out/lbit/a [video]
    PYTHONPATH=<new tree> python benchmarks/layout_bitwise.py save out/lbit/b
    python benchmarks/layout_bitwise.py compare out/lbit/a out/lbit/b

The script runs against either tree: where a function moved or a keyword was renamed, it
takes whichever spelling the tree has. A film is also read by the tracker's frame reader
and tracked (`save DIR video`: that part alone).
"""

import importlib
import inspect
import sys
import warnings
from pathlib import Path

import numpy as np
from bitwise import main


def _first(*paths):
    """The first of 'module:name' that this tree has."""
    for path in paths:
        module, name = path.split(":")
        try:
            return getattr(importlib.import_module(module), name)
        except (ImportError, AttributeError):
            continue
    raise ImportError(f"none of {paths}")


def _has_options() -> bool:
    """Whether this tree's tracker takes its options as one TrackOptions (storage among them)."""
    try:
        from clpde.tracking.options import TrackOptions
    except ImportError:
        return False
    return "storage" in getattr(TrackOptions, "__dataclass_fields__", {})


def _inpainting(res: dict) -> None:
    import clpde
    from clpde.data import damaged_astronaut

    _, dam, mask = damaged_astronaut()
    img = dam[100:196, 150:246].astype(np.float32) / 255
    m = mask[100:196, 150:246].copy()
    for method in ("exemplar", "structure-texture", "coherence", "navier-stokes"):
        res[f"inpaint_{method}"] = clpde.inpaint(
            img, m, channel_axis=-1, method=method, seed=0, progress=False
        )
    res["inpaint_default"] = clpde.inpaint(img, m, channel_axis=-1, progress=False)
    res["inpaint_transport_colour"] = clpde.inpaint(
        img,
        m,
        channel_axis=-1,
        method="transport",
        colour="rho-phi-psi",
        max_steps=40,
        progress=False,
    )
    grey = img.mean(axis=-1).astype(np.float64)
    res["inpaint_uint16"] = clpde.inpaint((grey * 65535).astype(np.uint16), m, progress=False)


def _sequence(n=48, frames=5, seed=0):
    rng = np.random.default_rng(seed)
    y, x = np.mgrid[:n, :n] + 0.0
    out, first = [], None
    for t in range(frames):
        inside = np.hypot(x - 16 - 1.5 * t, y - 24) < 9
        frame = 0.3 + 0.4 * inside + 0.05 * rng.normal(size=(n, n))
        out.append(frame.astype(np.float32))
        first = inside if first is None else first
    return np.stack(out), first


def _tracking(res: dict) -> None:
    import clpde

    frames, first = _sequence()
    tracker_init = inspect.signature(clpde.MorphingTracker.__init__).parameters
    keyword = "storage" if "storage" in tracker_init or _has_options() else "band_layout"
    for storage in ("lists", "bricks8x8", "bricks16x4"):
        masks = clpde.track(frames, first, progress=False, **{keyword: storage})
        res[f"track_{storage}"] = np.asarray(masks)
    masks, level_sets = clpde.track(
        frames,
        first,
        progress=False,
        return_level_sets=True,
        features="contrast",
        discrepancy="huber",
    )
    res["track_contrast_huber"], res["track_contrast_huber_phi"] = masks, level_sets


def _regions(res: dict) -> None:
    import clpde

    n, h = 48, 4.0 / 48  # bricks keep the band 9 cells from the border
    ax = (np.arange(n) - (n - 1) / 2) * h
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    phi = (np.sqrt(x**2 + y**2 + z**2) - 0.7).astype(np.float32)
    frames = clpde.track_region(
        phi,
        [(0.4 - z).astype(np.float32)],
        spacing=h,
        beta=0.5,
        t=0.2,
        saves=1,
        origin=(ax[0],) * 3,
        progress=False,
        keep_volumes=True,
        storage="bricks",
    )
    for k, f in enumerate(frames):
        res[f"regions_bricks_{k}_phi"] = f.phi
        res[f"regions_bricks_{k}_labels"] = f.face_labels


def _tracking_video(res: dict, out: Path) -> None:
    """A film read by the tracker's frame reader, and tracked."""
    import clpde

    read_frames = _first("clpde.io.frames:read_frames", "clpde.sequence_io:read_frames")
    writer = _first("clpde.io.video:VideoWriter", "clpde.video:VideoWriter")
    frames, first = _sequence()
    path = out / "track.mp4"
    with writer(path, 25) as w:
        for frame in frames:
            w.write(np.repeat((np.clip(frame, 0, 1) * 255).astype(np.uint8)[..., None], 3, -1))
    grey = read_frames(path)
    res["track_video_frames"] = grey
    res["track_video_masks"] = clpde.track(grey, first, progress=False)


def save(out: Path) -> None:
    import clpde

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    res: dict = {}
    parts = sys.argv[3].split(",") if len(sys.argv) > 3 else ["all"]
    if parts == ["all"]:
        for part in (_inpainting, _tracking, _regions):
            part(res)
    if "all" in parts or "video" in parts:
        _tracking_video(res, out)
    for name, value in res.items():
        np.save(out / f"{name}.npy", np.asarray(value))


if __name__ == "__main__":
    main(save, __doc__)
