"""Film restoration: inpaint every frame of a video (or a folder of images) over Dask workers.

``clpde inpaint VIDEO --mask MASK -o OUT.mp4`` reads the frames with PyAV, sends them in
batches to the workers (clpde.batch's cluster: a local one, or ``--scheduler``), and writes
the restored frames in their order with the input's frame rate, atomically. MASK is one
image for every frame or a folder of per-frame masks (in name order). A folder of images
in gives a folder of images out, under the same names.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from .._progress import progress_bar
from ..errors import InputError
from ..imagedata import split_alpha
from ..inpainting.api import inpaint
from ..io.frames import image_files
from ..io.images import check_output_folder, read_image, read_mask, write_image
from ..io.video import (
    READ_SUFFIXES,
    VIDEO_FORMATS,
    VideoWriter,
    is_video,
    iter_video,
    video_info,
)
from ..scale.cluster import connect


class _Sequence:
    """The frames of a video or of an image folder, read one at a time."""

    def __init__(self, path):
        self.path = Path(path)
        if self.path.is_dir():
            self.files = image_files(self.path)
            self.count, self.rate = len(self.files), Fraction(25)
        elif is_video(self.path):
            info = video_info(self.path)
            self.files, self.count, self.rate = None, info.frames, info.rate
        else:
            raise InputError(f"{self.path} is neither a video ({', '.join(sorted(READ_SUFFIXES))}) "
                             "nor a folder of images")

    def __iter__(self):
        if self.files is None:
            yield from iter_video(self.path)
        else:
            for p in self.files:
                yield read_image(p)

    def name(self, t: int) -> str:
        """The file name of frame t in an output folder: the input's, or frame_00000.png..."""
        return self.files[t].name if self.files is not None else f"frame_{t:05d}.png"


def _masks_for(mask, count_hint: int):
    """A function t -> mask path for frame t: one mask for all, or the t-th of a folder."""
    mask = Path(mask)
    if mask.is_dir():
        files = image_files(mask)
        if count_hint and len(files) != count_hint:
            raise InputError(f"the mask folder {mask} holds {len(files)} masks for "
                             f"{count_hint} frames; give one mask per frame (or one mask file)")

        def pick(t):
            if t >= len(files):
                raise InputError(f"the mask folder {mask} has no mask for frame {t}")
            return files[t]
        return pick
    if not mask.is_file():
        raise InputError(f"mask {mask} does not exist")
    return lambda t: mask


# ---- the task on a worker ---------------------------------------------------------------------
def inpaint_frames(frames, masks, options) -> list[np.ndarray]:
    """Inpaint each frame (rows, columns[, channels]) where its boolean mask is set."""
    out = []
    for frame, mask in zip(frames, masks, strict=False):
        if not mask.any():
            out.append(frame)
            continue
        parts = split_alpha(frame)
        result = inpaint(parts.colour, mask, channel_axis=parts.channel_axis, progress=False,
                         **options)
        out.append(parts.join(result).astype(frame.dtype))
    return out


# ---- the film restoration -------------------------------------------------------------------
@dataclass
class RestoreResult:
    output: Path
    frames: int
    rate: Fraction
    seconds: float
    cluster_seconds: float
    workers: int
    frames_sha256: str | None = None  # a video's frames before encoding (VideoWriter's)


def inpaint_sequence(source, mask, output, *, workers=None, threads=None, scheduler=None,
                     client=None, frames_per_task: int = 4, progress=None,
                     overwrite: bool = False, overwrite_option: str = "overwrite=True",
                     **options) -> RestoreResult:
    """Inpaint every frame of `source` (a video or an image folder) where `mask` (an image,
    or a folder of per-frame masks) is set, over Dask workers; write a video (`output`
    ends in .mp4, .mkv, .mov, .avi) with the input's frame rate, or an image folder.
    Options are clpde.inpaint's (max_steps, tol, dt, ...). An output folder follows
    clpde's folder rule: new or empty, or with `overwrite` one holding only clpde's kinds
    of output files (frames of the same names are replaced)."""

    if frames_per_task < 1:
        raise InputError(f"frames per task must be at least 1, not {frames_per_task}")
    sequence = _Sequence(source)
    output = Path(output)
    to_video = output.suffix.lower() in VIDEO_FORMATS
    if not to_video and output.suffix:
        raise InputError(f"output {output}: give a video ({', '.join(sorted(VIDEO_FORMATS))}) "
                         "or a folder for the restored frames")
    if output.resolve() == sequence.path.resolve():
        raise InputError(f"output {output} is the input; clpde never overwrites its inputs")
    mask_of = _masks_for(mask, sequence.count)
    start = time.perf_counter()
    if not to_video:

        check_output_folder(output, overwrite, option=overwrite_option)
        output.mkdir(exist_ok=True)
    writer = VideoWriter(output, sequence.rate) if to_video else None
    written = 0
    try:
        with connect(workers, scheduler, client, threads, device=options.get("device"),
                     tasks=max(1, sequence.count // frames_per_task)) as (live, info):
            written = _pipeline(live, sequence, mask_of, writer, output, frames_per_task,
                                options, progress, read_mask)
        if writer is not None:
            writer.close()
    except BaseException:
        if writer is not None:
            writer.abort()
        raise
    return RestoreResult(output, written, sequence.rate, time.perf_counter() - start,
                         info.get("seconds", 0.0), info["workers"],
                         writer.frames_sha256 if writer is not None else None)


def _pipeline(client, sequence, mask_of, writer, output, per_task, options, progress,
              read_mask) -> int:
    """Read, send in batches, and write in order, with a bounded number of batches in
    flight (memory stays proportional to the workers, not to the film)."""

    resources = None
    workers = client.scheduler_info()["workers"].values()
    if any("GPU" in (w.get("resources") or {}) for w in workers):
        resources = {"GPU": 1}
    window = max(2, 2 * len(workers))
    bar = progress_bar(progress, sequence.count or None, "clpde inpaint", unit="frame")
    pending, written, t = [], 0, 0
    frames = iter(sequence)
    mask_cache = {}

    def masks_for(batch_frames, first):
        out = []
        for k, frame in enumerate(batch_frames):
            path = mask_of(first + k)
            key = (path, frame.shape[:2])
            if key not in mask_cache:
                if len(mask_cache) > 8:  # per-frame masks: keep only the latest few
                    mask_cache.clear()
                mask_cache[key] = read_mask(path, frame.shape[:2], what="the frames")
            out.append(mask_cache[key])
        return out

    def drain(block: bool):
        nonlocal written
        while pending and (block or pending[0].done()):
            for frame in pending.pop(0).result():
                if writer is not None:
                    writer.write(frame)
                else:
                    write_image(output / sequence.name(written), frame)
                written += 1
                bar.update(1)

    try:
        done = False
        while not done:
            chunk = []
            for frame in frames:
                chunk.append(frame)
                if len(chunk) == per_task:
                    break
            done = len(chunk) < per_task
            if chunk:
                future = client.submit(inpaint_frames, chunk, masks_for(chunk, t), options,
                                       pure=False, resources=resources)
                pending.append(future)
                t += len(chunk)
            drain(block=False)
            if len(pending) >= window:
                pending[0].result()  # wait for the oldest batch (its error, if any, is raised)
                drain(block=False)
        drain(block=True)
    except BaseException:
        client.cancel(pending, force=True)
        raise
    finally:
        bar.close()
    if sequence.files is not None and written != len(sequence.files):
        raise InputError(f"read {written} of {len(sequence.files)} frames")
    return written
