"""Film restoration: inpaint every frame of a video (or a folder of images) over Dask workers.

``clpde inpaint VIDEO --mask MASK -o OUT.mp4`` reads the frames with PyAV, sends them in
batches to the workers (clpde.batch's cluster: a local one, or ``--scheduler``), and writes
the restored frames in their order with the input's frame rate, atomically. MASK is one
image for every frame or a folder of per-frame masks (in name order). A folder of images
in gives a folder of images out, under the same names.

H.264 in 4:2:0 needs even sizes: an odd-sized film is padded by one row or column (edge
pixels repeated) for the encoder, and its size is kept in the file's metadata so that
``read_video`` crops it back; frames are never rescaled.
"""

from __future__ import annotations

import contextlib
import hashlib
import re
import sys
import time
from dataclasses import dataclass
from fractions import Fraction
from pathlib import Path

import numpy as np

from .imagedata import InputError
from .io import IMAGE_FORMATS, atomic_output, read_image, write_image

VIDEO_FORMATS = {".mp4": "mp4", ".mov": "mov", ".mkv": "matroska", ".avi": "avi",
                 ".m4v": "mp4"}
READ_SUFFIXES = set(VIDEO_FORMATS) | {".webm", ".mpg", ".mpeg", ".ogv"}
_SIZE_TAG = "comment"  # container metadata: "clpde size=WxH" when the frames were padded
_SIZE_RE = re.compile(r"clpde size=(\d+)x(\d+)")


def is_video(path) -> bool:
    return Path(path).suffix.lower() in READ_SUFFIXES


def _av():
    try:
        import av
    except ImportError:
        raise InputError(
            'reading and writing video needs PyAV: pip install "clpde[batch]"'
        ) from None
    return av


# ---- video files ------------------------------------------------------------------------------
@dataclass
class VideoInfo:
    frames: int  # as the container states it (0 when unknown)
    rate: Fraction
    width: int
    height: int


def video_info(path) -> VideoInfo:
    av = _av()
    with _open_input(av, path) as container:
        stream = container.streams.video[0]
        width, height = _stored_size(container, stream)
        return VideoInfo(int(stream.frames or 0), _rate(stream), width, height)


@contextlib.contextmanager
def _open_input(av, path):
    path = Path(path)
    if not path.is_file():
        raise InputError(f"input video {path} does not exist")
    try:
        container = av.open(str(path))
    except Exception as exc:  # noqa: BLE001  (PyAV raises many types: all mean unreadable)
        raise InputError(f"cannot read {path} as a video: {exc}") from None
    try:
        if not container.streams.video:
            raise InputError(f"{path} holds no video stream")
        yield container
    finally:
        container.close()


def _rate(stream) -> Fraction:
    rate = stream.average_rate or stream.base_rate or stream.guessed_rate
    return Fraction(rate) if rate else Fraction(25)


def _stored_size(container, stream) -> tuple[int, int]:
    """The frames' size before padding (from our metadata), else the stream's."""
    match = _SIZE_RE.search(container.metadata.get(_SIZE_TAG, ""))
    width, height = stream.codec_context.width, stream.codec_context.height
    if match:
        w, h = int(match.group(1)), int(match.group(2))
        if w <= width and h <= height:
            return w, h
    return width, height


def iter_video(path):
    """The frames of a video as (rows, columns, 3) uint8 RGB arrays, in display order."""
    av = _av()
    with _open_input(av, path) as container:
        stream = container.streams.video[0]
        width, height = _stored_size(container, stream)
        try:
            for frame in container.decode(stream):
                # An array of its own: PyAV's shares the frame's buffer, and a batch of
                # frames waits (and is sent) while the next ones are decoded.
                yield np.array(frame.to_ndarray(format="rgb24")[:height, :width])
        except av.FFmpegError as exc:
            raise InputError(f"cannot decode {path}: {exc}") from None


def read_video(path) -> tuple[np.ndarray, Fraction]:
    """(frames (T, rows, columns, 3) uint8, frame rate) of a video file."""
    frames = list(iter_video(path))
    if not frames:
        raise InputError(f"{path} holds no frames")
    return np.stack(frames), video_info(path).rate


class VideoWriter:
    """Frames into a video file with PyAV (H.264, 4:2:0), written atomically: the file
    appears under its name only when close() succeeds; abort() (or an error in a with
    block) leaves nothing.

    Reproducible: the same frames give the same bytes, run after run and whatever ran in
    the process before. x264's macroblock-tree rate control reads memory that it never
    initialised (glibc's MALLOC_PERTURB_=1 alone changes a film from 105 to 124 kB), so
    with it a film restored over workers and one restored serially differed in bytes with
    the same frames; it is off (mbtree=0: 5% larger, 0.3 dB lower PSNR on the carphone clip
    at crf 17). threads: the encoder's (0: FFmpeg's choice); x264's output depends on their
    number, so the default 1 gives the same bytes on any machine.
    """

    def __init__(self, path, rate, *, crf: int = 17, codec: str = "libx264", threads: int = 1):
        path = Path(path)
        suffix = path.suffix.lower()
        if suffix not in VIDEO_FORMATS:
            raise InputError(f"{path}: write a video as one of {', '.join(sorted(VIDEO_FORMATS))}")
        if not path.parent.is_dir():
            raise InputError(f"output folder {path.parent} does not exist; create it first")
        if isinstance(threads, bool) or not isinstance(threads, int) or threads < 0:
            raise InputError(f"threads must be a whole number >= 0 (0: FFmpeg's choice), "
                             f"not {threads!r}")
        self.path, self.rate, self.crf, self.codec = path, Fraction(rate), crf, codec
        self.threads = threads
        self._atomic = atomic_output(path)
        self._tmp = self._atomic.__enter__()
        self._container = _av().open(str(self._tmp), mode="w", format=VIDEO_FORMATS[suffix])
        self._stream = None
        self.count = 0
        # The frames as given, before the (lossy) encoder: what a film restored over
        # workers and one restored serially must agree on, bit for bit.
        self._digest = hashlib.sha256()

    def _start(self, height: int, width: int) -> None:
        self.size = (height, width)
        stream = self._container.add_stream(self.codec, rate=self.rate)
        stream.width, stream.height = width + width % 2, height + height % 2
        stream.pix_fmt = "yuv420p"
        options = {"crf": str(self.crf)}
        if self.codec == "libx264":  # its mbtree reads uninitialised memory (see above)
            options["x264-params"] = "mbtree=0"
        stream.options = options
        stream.thread_count = self.threads
        if (stream.width, stream.height) != (width, height):
            self._container.metadata[_SIZE_TAG] = f"clpde size={width}x{height}"
        self._stream = stream

    def write(self, frame: np.ndarray) -> None:
        av = _av()
        frame = np.asarray(frame)
        if frame.ndim == 2:
            frame = np.repeat(frame[..., np.newaxis], 3, axis=-1)
        if frame.dtype != np.uint8 or frame.ndim != 3 or frame.shape[-1] not in (3, 4):
            raise InputError(f"video frames must be 8-bit grey or RGB, not {frame.dtype} "
                             f"of shape {frame.shape}")
        frame = np.ascontiguousarray(frame[..., :3])
        if self._stream is None:
            self._start(*frame.shape[:2])
        if frame.shape[:2] != self.size:
            raise InputError(f"frame {self.count} is {frame.shape[1]}x{frame.shape[0]}, the "
                             f"film {self.size[1]}x{self.size[0]}; all frames need one size")
        self._digest.update(frame.data)
        pad = ((0, self._stream.height - frame.shape[0]), (0, self._stream.width - frame.shape[1]),
               (0, 0))
        if any(p[1] for p in pad):
            frame = np.pad(frame, pad, mode="edge")
        picture = av.VideoFrame.from_ndarray(np.ascontiguousarray(frame), format="rgb24")
        picture.pts = self.count
        for packet in self._stream.encode(picture):
            self._container.mux(packet)
        self.count += 1

    @property
    def frames_sha256(self) -> str:
        """SHA-256 of the RGB frames written so far (rows, columns, 3 uint8 each, in order)."""
        return self._digest.hexdigest()

    def close(self) -> Path:
        if self._stream is None:
            self.abort()
            raise InputError(f"no frames to write to {self.path}")
        for packet in self._stream.encode():
            self._container.mux(packet)
        self._container.close()
        self._atomic.__exit__(None, None, None)
        return self.path

    def abort(self) -> None:
        with contextlib.suppress(Exception):
            self._container.close()
        with contextlib.suppress(BaseException):
            self._atomic.__exit__(KeyboardInterrupt, KeyboardInterrupt(), None)

    def __enter__(self):
        return self

    def __exit__(self, kind, value, tb):
        if kind is None:
            self.close()
        else:
            self.abort()


def write_video(path, frames, rate, *, threads: int = 1) -> Path:
    """Write (T, rows, columns[, 3]) uint8 frames as a video at `rate` frames per second
    (`threads`: the encoder's, see VideoWriter)."""
    with VideoWriter(path, rate, threads=threads) as writer:
        for frame in frames:
            writer.write(frame)
    return Path(path)


# ---- frame sequences: a video or a folder of images ------------------------------------------
def _natural_key(path: Path):
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def image_files(folder) -> list[Path]:
    folder = Path(folder)
    files = sorted(
        (p for p in folder.iterdir() if p.is_file() and p.suffix.lower() in IMAGE_FORMATS),
        key=_natural_key,
    )
    if not files:
        raise InputError(f"the folder {folder} holds no images (.png, .tif/.tiff, .jpg/.jpeg)")
    return files


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
    from .cli._common import split_alpha
    from .inpaint import inpaint

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
    from .batch import connect
    from .io import read_mask

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
        from .io import check_output_folder

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
    from ._progress import progress_bar

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


# ---- `clpde inpaint VIDEO --mask MASK -o OUT.mp4` ------------------------------------------------
def add_sequence_arguments(parser) -> None:
    """The options of `clpde inpaint` for a video or an image folder."""
    group = parser.add_argument_group(
        "films and frame folders", "IMAGE may be a video or a folder of images; MASK (or "
        "--mask) one image or a folder of per-frame masks; -o a video or a folder")
    group.add_argument("--mask", dest="mask_option", metavar="MASK", default=None,
                       help="the mask, as an option (same as the MASK argument)")
    group.add_argument("--workers", type=int, default=None, metavar="N",
                       help="local Dask workers for the frames (default: one per core)")
    group.add_argument("--scheduler", default=None, metavar="ADDRESS",
                       help="use a running Dask cluster, e.g. tcp://HOST:8786")
    group.add_argument("--frames-per-task", type=int, default=4, metavar="K",
                       help="frames sent to a worker at a time (default: 4)")


def prepare_sequence_args(args) -> bool:
    """Fold --mask into MASK; True when IMAGE is a video or a folder of frames."""
    option = getattr(args, "mask_option", None)
    if option is not None:
        if args.mask is not None:
            raise InputError("give the mask once: as MASK or as --mask")
        args.mask = option
    source = args.input
    sequence = bool(source) and (Path(source).is_dir() or is_video(source))
    if not sequence and (getattr(args, "workers", None) or getattr(args, "scheduler", None)):
        raise InputError("--workers and --scheduler apply to a video or a folder of frames; "
                         "for many image files use `clpde batch inpaint`")
    return sequence


def run_sequence_inpaint(args) -> int:
    if args.gif or args.demo:
        raise InputError("--gif and --demo apply to one image, not a video or frame folder")
    if not args.mask:
        raise InputError("give the mask: clpde inpaint VIDEO --mask MASK -o OUT.mp4")
    if args.workers is not None and args.scheduler is not None:
        raise InputError("give --workers or --scheduler, not both")
    from .cli.inpaint import TRANSPORT_OPTIONS

    # as for one image: only the options given, so that the default method is chosen by them
    options = {"colour": args.colour, "levels": args.levels, "device": args.device,
               "method": args.method, "grow": getattr(args, "grow", 0),
               "seed": getattr(args, "seed", None)}
    options.update({name: getattr(args, name) for name in TRANSPORT_OPTIONS
                    if getattr(args, name) is not None})
    result = inpaint_sequence(args.input, args.mask, args.output, workers=args.workers,
                              scheduler=args.scheduler, frames_per_task=args.frames_per_task,
                              overwrite=getattr(args, "overwrite", False),
                              overwrite_option="--overwrite", **options)
    print(f"inpaint: {result.frames} frames at {float(result.rate):.3f} fps in "
          f"{result.seconds:.1f} s on {result.workers} worker(s); wrote {result.output}",
          file=sys.stderr)
    return 0
