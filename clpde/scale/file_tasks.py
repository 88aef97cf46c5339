"""The file-to-file tasks behind the command line and the batch runner.

One library function per command, with plain arguments: the input path, the output path
and keyword options (no argparse). ``clpde COMMAND`` parses its flags into these keywords
and runs ``TASKS[COMMAND]``; ``clpde.batch`` runs the same functions on Dask workers. Each
reads its input, runs the library, writes its output atomically and returns the lines that
say what it did (the command line prints them; a batch keeps them quiet).
"""

from __future__ import annotations

import os
from collections.abc import Callable
from pathlib import Path

import numpy as np

from .._progress import on_terminal
from ..errors import InputError
from ..film.restore import restore_film
from ..imagedata import mask_plane, split_alpha
from ..inpainting.api import inpaint
from ..inpainting.registry import resolve
from ..io import frames as frame_io
from ..io.images import (
    _frame_to_uint8,
    check_folder_writable,
    check_not_overwriting_input,
    check_output_file,
    check_output_folder,
    check_writable,
    read_image,
    read_mask,
    write_gif,
    write_image,
)
from ..io.video import write_video
from ..io.video_probe import require_av
from ..planar import tiled
from ..planar.flows import diffuse
from ..planar.rof import denoise_tv
from ..runtime import get_runtime
from ..surface.runs import DATA_FLOWS, load_surface, mesh_colours, run_flow, write_run
from ..tracking.confidence import LOW_CONFIDENCE
from ..tracking.options import TrackOptions, track_options
from ..tracking.tracker import track

TRANSPORT_OPTIONS = ("dt", "scaling", "max_steps", "tol", "mean_tol")
OVERLAY_RATE = 10  # frames per second of the tracking overlay


def read_input(path, output, *others, device=None, allow_nan: bool = False) -> np.ndarray:
    """Check the device and the output path, then read the image at `path`; all before any
    work is done. NaN pixels are refused with the command that fills them, unless allow_nan."""
    get_runtime(device)  # an unknown device fails here, before reading anything
    check_not_overwriting_input([path, *others], output)
    check_output_file(output)  # before reading: a large input takes a while
    image = read_image(path)
    if image.dtype == bool:  # 1-bit files: compute on 0/255 and write 8-bit
        image = image.astype(np.uint8) * 255
    if not allow_nan and np.issubdtype(image.dtype, np.floating):
        bad = int((~np.isfinite(image)).sum())
        if bad:
            raise InputError(
                f"{path} has {bad} NaN or infinite values; fill them first with "
                f"`clpde inpaint {path} nan -o FILLED.tif`, then use FILLED.tif"
            )
    check_writable(output, image.dtype, image.shape)
    return image


def _progress(progress):
    return on_terminal() if progress is None else progress


# ---- images ------------------------------------------------------------------------------------
def diffuse_file(
    input,
    output,
    *,
    flow: str = "heat",
    steps: int = 100,
    dt=None,
    kappa=None,
    edge=None,
    eps=None,
    presmooth=None,
    device=None,
    tile: bool = False,
    progress=None,
) -> list[str]:
    """`clpde diffuse`: a planar flow (clpde.diffuse) on the image `input`, written to
    `output`. tile: run in tiles (bitwise equal) when True, or by itself when the image
    exceeds the device's largest allocation (None); False never."""
    params = {
        k: v
        for k, v in (("kappa", kappa), ("edge", edge), ("eps", eps), ("presmooth", presmooth))
        if v is not None
    }
    if tile is not False and _run_tiled(
        "diffuse", input, output, tile, device, flow=flow, steps=steps, dt=dt, params=params
    ):
        return [f"wrote {output}"]
    image = read_input(input, output, device=device)
    parts = split_alpha(image, input)
    result = diffuse(
        parts.colour,
        flow,
        steps=steps,
        dt=dt,
        channel_axis=parts.channel_axis,
        device=device,
        progress=_progress(progress),
        **params,
    )
    write_image(output, parts.join(result))
    return [f"wrote {output}"]


def denoise_file(
    input,
    output,
    *,
    sigma=None,
    weight=None,
    method: str = "primal-dual",
    eps=None,
    max_steps=None,
    per_channel: bool = False,
    device=None,
    tile: bool = False,
    progress=None,
) -> list[str]:
    """`clpde denoise`: TV denoising (clpde.denoise_tv) of the image `input`, written to
    `output`. tile: as for diffuse_file (tiles need weight, max_steps and primal-dual)."""
    if eps is not None and method != "gradient":
        raise InputError("--eps applies to --method gradient only")
    if tile is not False and _run_tiled(
        "denoise", input, output, tile, device, weight=weight, method=method, max_steps=max_steps
    ):
        return [f"wrote {output}"]
    image = read_input(input, output, device=device)
    parts = split_alpha(image, input)
    options = {"method": method}
    if per_channel:
        options["vectorial"] = False
    if eps is not None:
        options["eps"] = eps
    if max_steps is not None:
        options["max_steps"] = max_steps
    result, info = denoise_tv(
        parts.colour,
        sigma=sigma,
        weight=weight,
        channel_axis=parts.channel_axis,
        device=device,
        progress=_progress(progress),
        return_info=True,
        **options,
    )
    write_image(output, parts.join(result))
    state = "converged" if info.converged else "stopped at --max-steps"
    residual = float(np.sqrt(np.mean(info.residual_variance)))
    noise = ""
    if info.sigma is not None:
        levels = ", ".join(f"{s:.4g}" for s in np.atleast_1d(info.sigma))
        noise = f", noise sigma {'estimated' if info.sigma_estimated else 'given'} {levels}"
    return [
        f"wrote {output}",
        f"denoise: {info.steps} {method} iterations ({state}), residual std {residual:.4g}{noise}",
    ]


def _run_tiled(command, input, output, force, device, **options) -> bool:
    """Run diffuse / denoise in tiles when asked (force) or needed (the image exceeds the
    device); False when the untiled run should go ahead."""
    if not (force or tiled.may_exceed_device(input, device)):  # the header rules most images out
        return False
    image = read_input(input, output, device=device)
    parts = split_alpha(image, input)
    channels = 1 if parts.channel_axis is None else parts.colour.shape[-1]
    factor = 2 if command == "diffuse" else 4  # denoise: f, u and a two-component dual field
    needed = tiled.exceeds_device(parts.colour.shape, channels * factor // 2, device)
    if not (force or needed):
        return False
    if command == "diffuse":
        steps = options["steps"]
        chunks = 256 if not needed else tiled.device_chunks(channels, steps, device)
        result = tiled.diffuse(
            parts.colour,
            options["flow"],
            steps=steps,
            dt=options["dt"],
            channel_axis=parts.channel_axis,
            device=device,
            chunks=chunks,
            **options["params"],
        )
    else:
        weight, max_steps = options["weight"], options["max_steps"]
        if weight is None or options["method"] != "primal-dual" or max_steps is None:
            raise InputError(
                "tiled denoise needs --weight W and --max-steps N (a fixed "
                "iteration count) with --method primal-dual"
            )
        chunks = 256 if not needed else tiled.device_chunks(channels, max_steps, device, 4)
        result = tiled.denoise_tv(
            parts.colour,
            weight,
            max_steps,
            channel_axis=parts.channel_axis,
            device=device,
            chunks=chunks,
        )
    write_image(output, parts.join(result))
    return True


def _read_soft_mask(path, shape) -> np.ndarray:
    """The mask's grey level over its dtype's range as a float degree of damage in [0, 1]
    (a colour mask: its brightest colour channel; an alpha channel is ignored)."""
    mask = mask_plane(read_image(path))
    if mask.shape != tuple(shape):
        raise InputError(
            f"mask {path} is {mask.shape[1]}x{mask.shape[0]} pixels but the image "
            f"is {shape[1]}x{shape[0]}; give a mask of the same size"
        )
    if np.issubdtype(mask.dtype, np.integer):
        return mask.astype(np.float32) / np.iinfo(mask.dtype).max
    return np.clip(mask.astype(np.float32), 0, 1)


def _inpaint_mask(input, mask, image, soft_mask: bool):
    """The mask to fill: the file `mask` (binary, or soft), or the NaN pixels for 'nan'."""
    finite = (
        np.isfinite(image)
        if np.issubdtype(image.dtype, np.floating)
        else np.ones(image.shape, bool)
    )
    finite = finite.all(axis=-1) if finite.ndim == 3 else finite
    if str(mask).lower() == "nan" and not os.path.exists(mask):
        if finite.all():
            raise InputError(
                f"{input} has no NaN pixels to fill (MASK 'nan'); give a mask "
                "image of the pixels to inpaint"
            )
        return ~finite
    if soft_mask:
        omega = _read_soft_mask(mask, image.shape[:2])
    else:
        omega = read_mask(mask, image.shape[:2])
    if not finite[~(omega > 0)].all():
        raise InputError(
            f"{input} has {int((~finite[~(omega > 0)]).sum())} NaN pixels outside the mask "
            f"{mask}; paint them into the mask, or give 'nan' as MASK to fill exactly "
            "the NaN pixels"
        )
    return omega


def inpaint_options(
    method=None,
    *,
    gif: bool = False,
    levels=None,
    dt=None,
    scaling=None,
    max_steps=None,
    tol=None,
    mean_tol=None,
):
    """The options object of `clpde inpaint` and batch (the one place they are built): the
    flags given (not None) override the method's defaults, checked once. No method with
    --gif (the evolution a GIF shows is the thesis scheme's) or a transport flag: transport."""
    flags = dict(dt=dt, scaling=scaling, max_steps=max_steps, tol=tol, mean_tol=mean_tol)
    given = {k: v for k, v in {**flags, "levels": levels}.items() if v is not None}
    if method is None and gif:
        method = "transport"
    return resolve(method, None, given)[1]


def inpaint_file(
    input,
    output,
    *,
    mask,
    method=None,
    colour: str = "channels",
    levels=None,
    soft_mask: bool = False,
    gif=None,
    gif_every: int = 100,
    dt=None,
    scaling=None,
    max_steps=None,
    tol=None,
    mean_tol=None,
    grow: float = 0,
    seed=None,
    device=None,
    progress=None,
) -> list[str]:
    """`clpde inpaint`: fill the image `input` where the image `mask` is set (or its NaN
    pixels, for mask 'nan'), written to `output`; gif: also the evolution as a GIF (the
    transport's, every gif_every steps). The method's options are built by
    inpaint_options (checked before the image is read); the others are clpde.inpaint's."""
    if gif_every < 1:
        raise InputError(f"--gif-every must be at least 1, not {gif_every}")
    options = inpaint_options(
        method,
        gif=bool(gif),
        levels=levels,
        dt=dt,
        scaling=scaling,
        max_steps=max_steps,
        tol=tol,
        mean_tol=mean_tol,
    )
    if gif:
        check_not_overwriting_input([input, mask], gif)
        if not str(gif).lower().endswith(".gif"):
            raise InputError(f"--gif {gif}: the animation must be a .gif file")
        folder = os.path.dirname(os.path.abspath(gif))
        if not os.path.isdir(folder):
            raise InputError(f"the folder {folder} for --gif does not exist; create it first")
        check_folder_writable(folder, gif)
    nan_mask = str(mask).lower() == "nan" and not os.path.exists(mask)
    image = read_input(input, output, *([] if nan_mask else [mask]), device=device, allow_nan=True)
    omega = _inpaint_mask(input, mask, image, soft_mask)
    parts = split_alpha(image, input)
    result, info = inpaint(
        parts.colour,
        omega,
        channel_axis=parts.channel_axis,
        colour=colour,
        device=device,
        progress=_progress(progress),
        return_info=True,
        options=options,
        grow=grow,
        seed=seed,
        snapshots=gif_every if gif else None,
    )
    write_image(output, parts.join(result))
    lines = [f"wrote {output}"]
    if gif:
        frames = evolution_frames(parts.colour, [s.image for s in info.snapshots])
        write_gif(gif, frames, duration=0.25)
        lines.append(
            f"wrote {gif} ({len(frames)} frames: the damaged image, then every "
            f"{gif_every} steps from the start fill to the result)"
        )
    if info.method is None:  # the empty mask's warning has said why
        lines.append("inpaint: 0 pixels to fill; wrote an unchanged copy")
        return lines
    state = "converged" if info.converged else "stopped at --max-steps"
    steps = (
        f"{info.steps} steps ({state}), {info.levels} level(s), "
        if info.method == "transport"
        else ""
    )
    chosen = f" (mostly {info.chosen})" if info.method == "auto" else ""
    lines.append(
        f"inpaint: {info.omega_pixels} pixels, method {info.method}{chosen}, {steps}"
        f"{len(info.boxes)} box(es), {info.seconds:.2f} s"
    )
    return lines


def evolution_frames(damaged, states) -> list[np.ndarray]:
    """The GIF's frames as uint8: the damaged image first (its region shown as it came, NaN
    as black), then the states; all on one intensity scale (the result's range for floats),
    consecutive equal frames merged, since a GIF cannot show them apart."""
    frames = [np.asarray(damaged), *(np.asarray(s) for s in states)]
    result = frames[-1]
    if np.issubdtype(result.dtype, np.floating):
        finite = result[np.isfinite(result)]
        lo, hi = (float(finite.min()), float(finite.max())) if finite.size else (0.0, 1.0)
        scale = hi - lo if hi > lo else 1.0
        frames = [
            np.nan_to_num((f.astype(np.float64) - lo) / scale, nan=0.0, posinf=1.0, neginf=0.0)
            for f in frames
        ]
    out = []
    for frame in map(_frame_to_uint8, frames):
        if not out or not np.array_equal(frame, out[-1]):
            out.append(frame)
    return out


# ---- folders of results --------------------------------------------------------------------
def tracking_options(*, motion=TrackOptions.motion, equalize="none", **flags) -> TrackOptions:
    """The TrackOptions of `clpde track` and batch (the one place they are built): motion
    'none' is None, equalize 'none' is False; `flags` are TrackOptions' other fields."""
    if flags.get("shape_weight", 0) < 0:
        raise InputError(f"--shape-weight must be at least 0, not {flags['shape_weight']}")
    return track_options(
        motion=None if motion == "none" else motion,
        equalize=False if equalize == "none" else equalize,
        **flags,
    )


def track_file(
    input,
    output,
    *,
    mask,
    features: str = TrackOptions.features,
    colour: bool = TrackOptions.colour,
    discrepancy: str = TrackOptions.discrepancy,
    motion: str = TrackOptions.motion,
    shape_weight: float = TrackOptions.shape_weight,
    region_weight=TrackOptions.region_weight,
    curvature=TrackOptions.curvature,
    equalize: str = "none",
    smooth: bool = TrackOptions.smooth,
    max_iterations=TrackOptions.max_iterations,
    min_size: int = TrackOptions.min_size,
    frames=None,
    gif: bool = True,
    mp4: bool = False,
    low_confidence=None,
    overwrite: bool = False,
    device=None,
    progress=None,
) -> list[str]:
    """`clpde track`: the object marked by the image `mask` in the first frame of `input`
    (a video, an image folder or a multi-page TIFF) followed through it (clpde.track); the
    folder `output` gets the masks, contours.json and overlay.gif (and overlay.mp4)."""
    options = tracking_options(
        features=features,
        colour=colour,
        discrepancy=discrepancy,
        motion=motion,
        shape_weight=shape_weight,
        region_weight=region_weight,
        curvature=curvature,
        equalize=equalize,
        smooth=smooth,
        max_iterations=max_iterations,
        min_size=min_size,
    )
    get_runtime(device)
    check_not_overwriting_input([input, mask], output)
    check_output_folder(output, overwrite, option="--overwrite")
    if mp4:
        require_av()
    threshold = LOW_CONFIDENCE if low_confidence is None else low_confidence
    if not 0 < threshold <= 1:
        raise InputError(f"--low-confidence must be in (0, 1], not {threshold}")
    shown = frame_io.read_frames(input, grey=False)  # the overlays show the frames' colours
    if frames is not None:
        if frames < 1:
            raise InputError(f"--frames must be at least 1, not {frames}")
        shown = shown[:frames]
    images = frame_io.to_grey(shown) if shown.ndim == 4 and not colour else shown
    first = read_mask(
        mask,
        images.shape[1:3],
        what="the frames",
        fix="draw the mask on the first frame at its size",
    )
    masks, confidence = track(
        images,
        first,
        options=options,
        device=device,
        progress=_progress(progress),
        return_confidence=True,
    )
    written = frame_io.write_tracking(output, shown, masks, gif=gif, overwrite=overwrite)
    if mp4:
        written.append(_write_mp4(output, shown, masks))
    lines = [f"track: {len(masks)} frames; wrote {len(written)} files to {output}"]
    low = [int(k) for k in np.nonzero(np.asarray(confidence) < threshold)[0]]
    if low:
        lines.append(
            f"track: low confidence (below {threshold:g}) in frames {', '.join(map(str, low))}"
        )
    return lines


def _write_mp4(outdir, frames, masks):
    """overlay.mp4 beside the GIF, by the one video writer (io/video.py, atomic)."""
    final = Path(outdir) / "overlay.mp4"
    write_video(
        final, [frame_io.overlay(f, m) for f, m in zip(frames, masks, strict=False)], OVERLAY_RATE
    )
    return final


def surface_file(
    input,
    output,
    *,
    flow: str,
    resolution: int = 96,
    t=None,
    iterations=None,
    sigma: float = 0.15,
    data: str = "auto",
    direction: str = "major",
    size: int = 400,
    seed: int = 0,
    storage: str = "lists",
    on=None,
    overwrite: bool = False,
    device=None,
    progress=None,
) -> list[str]:
    """`clpde surface`: one of clpde.surface.runs.FLOWS on the surface of the mesh `input`
    (a file, or a shape name of clpde.surface.SURFACE_SHAPES); the folder `output` gets the
    pictures before and after and the coloured result as PLY and GLB."""
    get_runtime(device)
    check_not_overwriting_input([input], output)
    check_output_folder(output, overwrite, option="--overwrite")
    if resolution < 16:
        raise InputError(f"--resolution must be at least 16, not {resolution}")
    if size < 16:
        raise InputError(f"--size must be at least 16, not {size}")
    if direction == "none" and flow == "flowvis":
        raise InputError("flowvis needs --direction major or minor")
    surf = load_surface(input, resolution, device=device)
    surf.storage = storage
    # the results go on the user's own mesh (its vertices' values) unless asked otherwise
    on_input = (on or "input") == "input" and getattr(surf, "mesh", None) is not None
    if on == "input" and not on_input:
        raise InputError(
            f"--on input needs a mesh file; {input!r} is a generated shape, "
            "whose results are written on a marching-cubes mesh (--on remesh)"
        )
    values = None
    if data != "pattern" and flow in DATA_FLOWS:
        values = mesh_colours(surf)
        if values is None and data == "mesh":
            raise InputError(f"{input} has no vertex colours; use --data pattern")
    run = run_flow(
        surf,
        flow,
        t=t,
        iterations=iterations,
        sigma=sigma,
        seed=seed,
        direction=direction,
        data=values,
        progress=_progress(progress),
    )
    written = write_run(run, output, size=size, overwrite=overwrite, on_input=on_input)
    return [
        f"surface {flow}: {run.note}; grid {'x'.join(map(str, surf.shape[::-1]))}, band "
        f"{surf.ext_band.n} cells; wrote {len(written)} files to {output}"
    ]


def restore_file(
    input,
    output,
    *,
    mask=None,
    masks_out=None,
    grow: float = 0,
    overlay=None,
    codec=None,
    overwrite: bool = False,
    device=None,
    progress=None,
    frames=None,
) -> list[str]:
    """`clpde restore` for one film or frame folder (clpde.film.restore.restore_film): the
    damage found (or the masks given) filled from the neighbouring frames, film in, film
    out, in this process."""
    get_runtime(device)
    options = dict(mask=mask, masks_out=masks_out, grow=grow, overlay=overlay, codec=codec)
    result = restore_film(
        input, output, overwrite=overwrite, progress=_progress(progress), frames=frames, **options
    )
    rate = result.frames / result.seconds if result.seconds else 0.0
    return [
        f"restore: {result.frames} frames ({rate:.2f} frames/s), "
        f"{result.masked_pixels} pixels filled; wrote {result.output}"
    ]


# command -> its task; every task takes (input, output, **options) and returns its report
TASKS: dict[str, Callable[..., list[str]]] = {
    "inpaint": inpaint_file,
    "denoise": denoise_file,
    "diffuse": diffuse_file,
    "track": track_file,
    "surface": surface_file,
    "restore": restore_file,
}
