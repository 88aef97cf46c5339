"""A film restored on Dask's workers, in chunks of frames that overlap by the temporal window.

The client reads the film once, in order, and sends each chunk, a run of whole blocks of
clpde.film.stream's grid with their windows' context on both sides, to a worker, which
restores it with :func:`clpde.film.stream.run_chunk`; the client writes the results back in
frame order. A worker is given exactly the arrays that one process gives the same functions
(the grid does not depend on the chunks), so the frames come out bit for bit as from
:func:`clpde.film.stream.restore_stream`. Only a few chunks are in flight at a time, so the
client's memory stays bounded by the workers' number, not by the film's length.
"""

from __future__ import annotations

from collections import deque
from collections.abc import Iterable, Iterator

import numpy as np

from ..errors import InputError
from .stream import DEFAULT_BLOCK, Block, WindowWork, iter_spans, plan_blocks, run_chunk


def plan_chunks(blocks: list[Block], blocks_per_chunk: int) -> list[list[Block]]:
    """Consecutive blocks grouped into chunks of `blocks_per_chunk` (the last may be shorter).

    Parameters
    ----------
    blocks : list of Block
        The grid (clpde.film.stream.plan_blocks).
    blocks_per_chunk : int
        Blocks per chunk, >= 1.

    Returns
    -------
    list of list of Block
        The chunks in frame order.

    Raises
    ------
    InputError
        If `blocks_per_chunk` is below 1.

    Examples
    --------
    >>> from clpde.film.stream import plan_blocks
    >>> [len(c) for c in plan_chunks(plan_blocks(10, 2, 1), 2)]
    [2, 2, 1]
    """
    if (
        isinstance(blocks_per_chunk, bool)
        or int(blocks_per_chunk) != blocks_per_chunk
        or blocks_per_chunk < 1
    ):
        raise InputError(f"a chunk must hold at least 1 block, not {blocks_per_chunk!r}")
    return [blocks[k : k + blocks_per_chunk] for k in range(0, len(blocks), blocks_per_chunk)]


def restore_chunked(
    client,
    frames: Iterable[np.ndarray],
    count: int,
    work: WindowWork,
    *,
    masks: Iterable[np.ndarray] | None = None,
    block: int = DEFAULT_BLOCK,
    chunk_frames: int | None = None,
    in_flight: int | None = None,
    span: tuple[int, int] | None = None,
) -> Iterator[tuple[np.ndarray, np.ndarray, np.ndarray | None]]:
    """Restore a film over a Dask cluster, yielding its frames in order.

    Parameters
    ----------
    client : distributed.Client
        The cluster to run on.
    frames : iterable of ndarray
        The film's `count` frames in order.
    count : int
        The number of frames.
    work : WindowWork
        The detector and filler (pickled to the workers).
    masks : iterable of ndarray, optional
        Given masks, one per frame (then nothing is detected).
    block : int
        Frames per block of the grid (the same as a one-process run's for the same frames).
    chunk_frames : int, optional
        Frames per chunk, rounded up to whole blocks (default: 4 blocks).
    in_flight : int, optional
        Chunks sent ahead of the one being written (default: twice the workers).
    span : (int, int), optional
        Restore only the frames [start, stop) (clpde.film.stream.plan_blocks).

    Yields
    ------
    (ndarray, ndarray, ndarray or None)
        Each frame restored, its mask and its defect kinds, in frame order.

    Raises
    ------
    InputError
        For a chunk size below 1; a worker's error is raised as it was.

    Examples
    --------
    >>> for frame, mask, kinds in restore_chunked(client, frames, 300, work):  # doctest: +SKIP
    ...     writer.write(frame)
    """
    if chunk_frames is not None and (isinstance(chunk_frames, bool) or chunk_frames < 1):
        raise InputError(f"a chunk must hold at least 1 frame, not {chunk_frames!r}")
    detecting = masks is None
    grid = plan_blocks(count, block, work.context(detecting), span)
    per_chunk = 4 if chunk_frames is None else -(-int(chunk_frames) // block)
    chunks = plan_chunks(grid, per_chunk)
    workers = client.scheduler_info()["workers"].values()
    resources = {"GPU": 1} if any("GPU" in (w.get("resources") or {}) for w in workers) else None
    limit = in_flight or max(2, 2 * len(workers))
    spans = iter_spans(frames, [(c[0].first, c[-1].last) for c in chunks], masks)
    pending: deque = deque()
    try:
        for chunk, (window, window_masks) in zip(chunks, spans, strict=True):
            data = client.scatter(window, direct=False)
            given = None if window_masks is None else client.scatter(window_masks, direct=False)
            pending.append(
                client.submit(run_chunk, work, data, given, chunk, pure=False, resources=resources)
            )
            while len(pending) >= limit or (pending and pending[0].done()):
                yield from _frames_of(pending.popleft())
        while pending:
            yield from _frames_of(pending.popleft())
    except BaseException:
        client.cancel(list(pending), force=True)
        raise


def _frames_of(future):
    restored, found, kinds = future.result()
    future.release()
    for k in range(len(restored)):
        yield restored[k], found[k], None if kinds is None else kinds[k]
