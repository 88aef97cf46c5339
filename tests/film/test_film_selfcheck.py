"""The fill's self-check for spatially detected damage (issue 34): a line scratch that every
neighbour carries is repaired on its own evidence (its deviation beyond its flanks), a
scratch false alarm is not; the frame before a scratch begins at a film's start gets no
scratch of its own (the ghost of its neighbours'); the window machinery hands the
detector's kinds to a filler that takes them."""

import numpy as np
import pytest
from scipy import ndimage
from scipy.ndimage import gaussian_filter

import clpde
from clpde.film import SCRATCH
from clpde.film.fill import line_evidence, ring_evidence
from clpde.film.stream import KEEP, WindowWork, restore_stream

T, NY, NX = 5, 72, 96


def _scene(rng, ny=NY, nx=NX):
    s = gaussian_filter(rng.random((ny, nx)), 2.0)
    return 0.3 + 0.4 * (s - s.min()) / (s.max() - s.min())


def _grainy(frames, rng, grain=0.01):
    return np.clip(frames + grain * rng.standard_normal(frames.shape), 0, 1).astype(np.float32)


def _harm(out, before):
    """The share of a frame's pixels changed by more than 10 grey levels (issue 34)."""
    return float((np.abs(out - before) > 10 / 255).mean())


def test_scratch_every_neighbour_carries_is_repaired_and_a_false_alarm_is_not(rng):
    """A still shot with fine texture; a dark scratch at one place in frames 1-4, flagged
    there (so that no neighbour sees it clean: the temporal residual says nothing), and
    flagged in frame 0 too, which has none (a detector's false alarm before a scratch
    begins). Given the kinds, frames 1-4 are repaired (their line stands out of its
    flanks) and frame 0 keeps its texture (no line there: a repair would smooth it).
    Without the kinds the self-check granted such a region the noise alone and kept
    every scratch."""
    scene = _scene(rng)
    scene[:, 28:44] += 0.1 * rng.random((NY, 16))  # the texture under the scratch
    clean = _grainy(np.repeat(scene[None], T, axis=0), rng)
    dirty = clean.copy()
    dirty[1:, 4:68, 35:37] -= 0.2
    masks = np.zeros((T, NY, NX), bool)
    masks[:, 4:68, 34:38] = True
    kinds = np.where(masks, SCRATCH, 0).astype(np.int8)
    out = clpde.inpaint_video(dirty, masks, keep=KEEP, kinds=kinds)
    band = (slice(4, 68), slice(35, 37))
    for t in range(1, T):
        before = np.abs(dirty[t][band] - clean[t][band]).mean()
        assert np.abs(out[t][band] - clean[t][band]).mean() < 0.25 * before, t
    assert _harm(out[0], dirty[0]) == 0
    # the test's false alarm is one a fill without the self-check harms (the spatial
    # fill: since filmfill2 a scratch's own fill takes out a profile, which frame 0 lacks)
    assert _harm(clpde.inpaint_video(dirty, masks)[0], dirty[0]) > 0.005
    old = clpde.inpaint_video(dirty, masks, keep=KEEP)
    for t in range(1, T):
        before = np.abs(dirty[t][band] - clean[t][band]).mean()
        assert np.abs(old[t][band] - clean[t][band]).mean() > 0.5 * before, t


def test_line_evidence_reads_no_line_on_an_edge():
    """An edge under a line's mask: the pixel against the worse of its flanks shows none
    (a ramp between two levels is no line); a bright line on the edge does."""
    g = np.zeros((8, 20), np.float32)
    g[:, 10:] = 0.6
    g[:, 9:11] = [0.2, 0.4]  # the edge's ramp
    lines = np.zeros(g.shape, bool)
    lines[:, 9:11] = True
    assert line_evidence(g, lines).max() == 0
    g[:, 9:11] = 0.9
    assert line_evidence(g, lines)[lines].min() > 0.08


def test_no_ghost_scratch_before_a_scratch_begins_at_the_start(rng):
    """A pan; a bright scratch from frame 1 on, fixed in the frame. Frame 0's residual
    against frames 1 and 2 (both on one side, both carrying it) shows the scratch's ghost,
    dark, where frame 0 has none; frame 0 gets no scratch, frames 1.. keep theirs."""
    n = 6
    scene = _scene(rng, NY, NX + 2 * n)
    clean = _grainy(np.stack([scene[:, 2 * t : 2 * t + NX] for t in range(n)]), rng)
    dirty = clean.copy()
    dirty[1:, 4:68, 47:49] = np.minimum(dirty[1:, 4:68, 47:49] + 0.25, 1.0)
    mask, kinds = clpde.detect_defects(dirty, return_kinds=True)
    assert (kinds[1:, 4:68, 47:49] == SCRATCH).mean() > 0.8
    assert not (kinds[0] == SCRATCH).any()
    assert mask[0].sum() < 20


def test_windows_hand_the_kinds_to_a_filler_that_takes_them():
    """A filler that says it takes the kinds gets, for each window, the detector's kinds of
    the frames it fills; one that does not is called as before; given masks bring none."""
    film = np.zeros((7, 8, 8), np.uint8)

    def detect(frames, channel_axis=None):
        masks = np.zeros(frames.shape, bool)
        masks[:, 2, 2] = True
        kinds = np.where(masks, SCRATCH, 0).astype(np.int8)
        kinds[:, 2, 2] = frames[:, 0, 0]  # each frame's number, to check the alignment
        return masks, kinds

    seen = []

    def fill(frames, masks, channel_axis=None, kinds=None):
        seen.append(None if kinds is None else (frames[:, 0, 0].tolist(), kinds[:, 2, 2].tolist()))
        return frames

    film[:, 0, 0] = np.arange(7)
    work = WindowWork(fill=fill, detect=detect, fill_radius=1, detect_radius=1, fill_kinds=True)
    list(restore_stream(film, 7, work, block=3))
    assert seen and all(f == k for f, k in seen)
    seen.clear()
    list(restore_stream(film, 7, WindowWork(fill=fill, detect=detect, fill_radius=1), block=3))
    assert seen == [None] * 3
    seen.clear()
    list(restore_stream(film, 7, work, masks=film > 100, block=3))
    assert seen == []  # given masks, none set: nothing to fill


def test_kinds_of_the_wrong_size_are_refused(rng):
    frames = rng.random((3, 16, 16)).astype(np.float32)
    masks = np.zeros(frames.shape, bool)
    masks[1, 4:8, 4:8] = True
    with pytest.raises(clpde.InputError, match="one kind per mask pixel"):
        clpde.inpaint_video(frames, masks, keep=KEEP, kinds=np.zeros((3, 16, 8), np.int8))


def test_scratch_a_neighbour_carries_unflagged_is_repaired(rng):
    """A still textured shot; a dark scratch in frames 2 and 3 at one place, flagged in
    frame 2 only (the detector missed it in frame 3), and frames 0, 1 and 4 flagged there
    for damage of their own: frame 3 is frame 2's only candidate, and it carries the
    scratch, so no two candidates agree, the spatial fill takes the line, and the residual
    against frame 3 says nothing changed. The line's deviation beyond its flanks says it
    did: frame 2 is repaired (before filmbudget the whole scratch was kept: its E^2 was
    frame 3's residual alone), and frame 3, unflagged, is left as it was."""
    scene = _scene(rng)
    scene[:, 28:44] += 0.1 * rng.random((NY, 16))
    clean = _grainy(np.repeat(scene[None], T, axis=0), rng)
    dirty = clean.copy()
    dirty[2:4, 4:68, 35:37] -= 0.2
    masks = np.zeros((T, NY, NX), bool)
    masks[[0, 1, 2, 4], 4:68, 34:38] = True
    kinds = np.where(masks, SCRATCH, 0).astype(np.int8)
    kinds[[0, 1, 4]] = np.where(masks[[0, 1, 4]], 1, 0)  # their own blotches, no line
    out = clpde.inpaint_video(dirty, masks, keep=KEEP, kinds=kinds)
    band = (slice(4, 68), slice(35, 37))
    before = np.abs(dirty[2][band] - clean[2][band]).mean()
    assert np.abs(out[2][band] - clean[2][band]).mean() < 0.25 * before
    assert np.abs(out[3] - dirty[3]).max() < 1e-6  # unflagged: left as it was


def test_ring_evidence_reads_beyond_a_soft_rim():
    """A blotch's soft rim (dirt blended into the scene, 1-2 px beyond what was detected)
    must not count as the scene: the evidence is read on the detector's ring, 3-5 px out,
    so the core's full distance outside the scene's range is kept (a ring 2-4 px out reads
    the rim's 0.4 and keeps less than half)."""
    spots = np.zeros((40, 40), bool)
    spots[16:24, 16:24] = True
    # the steps out from the blotch, as the rings count them (4-connected)
    d = ndimage.distance_transform_cdt(~spots, metric="taxicab")
    g = np.select([spots, d == 1, d == 2], [0.2, 0.3, 0.4], 0.5).astype(np.float32)
    ev = ring_evidence(g, spots, spots)
    assert np.allclose(ev[spots], 0.09, atol=1e-6)
