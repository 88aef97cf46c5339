"""The held-out stop (clpde/inpainting/holdout.py) of the transport (its default where the
surround repeats) and of Navier-Stokes (its default): on a periodic pattern with holes
deeper than its period neither falls far below its own biharmonic start (at their own
steady state they did, by 1.5-4 dB), thin damage keeps the method's own stop bit for bit,
and so do the transport's boxes in a surround that does not repeat."""

import numpy as np
import pytest

import clpde
from clpde.inpainting import holdout
from tests.cases import inpaint_corpus as corpus


def _periodic_case(seed):
    """A case of the inpainting corpus's periodic class: 6 holes 8-20 px across."""
    rng = np.random.default_rng(corpus._seed(f"periodic-{seed}", "periodic"))
    truth = corpus.periodic(seed)
    return truth, corpus.damage("periodic", truth, rng)


def _psnr(truth, result, mask):
    d = result.astype(float)[mask] - truth.astype(float)[mask]
    return 10 * np.log10(255.0**2 / np.mean(d * d))


# crossed gratings for the transport, a brick lattice for Navier-Stokes: where each fell
# furthest below its start
@pytest.mark.parametrize("method,seed", [("transport", 0), ("navier-stokes", 4)])
def test_periodic_pattern_stays_near_the_smooth_start(method, seed):
    truth, mask = _periodic_case(seed)
    damaged = np.where(mask, 0, truth).astype(np.uint8)

    def fill(method, **options):
        out = clpde.inpaint(damaged, mask, method=method, progress=False, **options)
        return _psnr(truth, out, mask)

    # the biharmonic fill both methods start from: the transport without a step
    start = fill("transport", max_steps=0, levels=1)
    own_stop = fill(method, holdout=0)
    held_out = fill(method)  # both methods' default
    assert own_stop < start - 1.0, (own_stop, start)  # what the held-out stop repairs
    assert held_out > start - 0.5, (held_out, start)
    assert held_out > own_stop + 1.0, (held_out, own_stop)


@pytest.mark.parametrize("method", ["transport", "navier-stokes"])
def test_thin_damage_keeps_the_methods_own_stop(method):
    truth = corpus.periodic(0, size=64)
    mask = np.zeros(truth.shape, bool)
    mask[20:23, 5:60] = True  # 3 px: thinner than the hidden ring
    mask[40:60, 30] = True
    damaged = np.where(mask, 0, truth).astype(np.uint8)
    a = clpde.inpaint(damaged, mask, method=method, progress=False, holdout=holdout.WIDTH)
    b = clpde.inpaint(damaged, mask, method=method, progress=False, holdout=0)
    np.testing.assert_array_equal(a, b)


def test_transport_validates_only_where_the_surround_repeats():
    # the corpus's calibration blobs on the camera crop, where "all" moved the stop (+1.1 dB
    # there, -1.4 on another photo): the default is the thesis's own stop, bit for bit
    truth = corpus._crop(corpus._skimage("camera"), 80, 200)
    mask = corpus.damage("blobs", truth, np.random.default_rng(corpus._seed("camera-0", "blobs")))
    damaged = np.where(mask, 0, truth).astype(np.uint8)
    assert holdout.ring(mask, holdout.WIDTH) is not None
    assert not holdout.periodic_surround(truth[None] / 255.0, mask)

    def fill(**options):
        return clpde.inpaint(damaged, mask, method="transport", progress=False, **options)

    default = fill()
    np.testing.assert_array_equal(default, fill(holdout=0))
    assert not np.array_equal(default, fill(holdout_where="all"))
    # and a periodic pattern is validated by default: the default differs from the own stop
    truth, mask = _periodic_case(2)
    assert holdout.periodic_surround(truth[None] / 255.0, mask)


def test_structure_texture_keeps_the_transports_own_stop():
    from clpde.inpainting import structure_texture

    solve = structure_texture._structure_solver("transport")
    assert solve.keywords == {"holdout": 0}


def test_holdout_where_is_checked():
    with pytest.raises(clpde.InputError, match="holdout_where"):
        clpde.inpaint(
            np.zeros((8, 8)), np.eye(8, dtype=bool), method="transport", holdout_where="edges"
        )


def test_ring_only_around_holes_at_least_its_width_deep():
    omega = np.zeros((40, 40), bool)
    omega[10:13, 5:35] = True  # 3 px thick: deepest pixel 2 px from a known one
    assert holdout.ring(omega, 4) is None
    omega[20:32, 10:22] = True  # 12 px: deep enough
    band = holdout.ring(omega, 4)
    assert band is not None and not (band & omega).any()
    from scipy import ndimage

    dist = ndimage.distance_transform_edt(~omega)
    assert band.sum() == ((dist > 0) & (dist <= 4)).sum()
    assert holdout.ring(omega, 0) is None


def test_tracker_keeps_the_own_stop_unless_clearly_better():
    band = np.zeros((4, 4), bool)
    band[1, 1:3] = True
    truth = np.zeros((1, 4, 4))
    tracker = holdout.Tracker(truth, band)
    for steps, err in ((0, 0.3), (34, 0.2), (68, 0.1)):
        tracker.add(steps, np.full((1, 4, 4), err))
    assert tracker.best() is None  # the last state fills the ring best
    tracker.add(102, np.full((1, 4, 4), 0.1 / np.sqrt(holdout.GAIN) * 0.999))
    assert tracker.best() is None  # better by less than the margin
    tracker.add(136, np.full((1, 4, 4), 0.2))
    assert tracker.best() == 68


def test_tracker_risen_once_clearly_above_its_least():
    band = np.zeros((4, 4), bool)
    band[1, 1:3] = True
    tracker = holdout.Tracker(np.zeros((1, 4, 4)), band)
    tracker.add(0, np.full((1, 4, 4), 0.1))
    assert not tracker.risen()  # one state: nothing to compare
    tracker.add(34, np.full((1, 4, 4), 0.1 * np.sqrt(holdout.RISE) * 0.999))
    assert not tracker.risen()  # above its least by less than RISE
    tracker.add(68, np.full((1, 4, 4), 0.1 * np.sqrt(holdout.RISE) * 1.001))
    assert tracker.risen()
    assert tracker.best() == 0  # where it stops, the least is the choice


def test_navier_stokes_run_stops_where_its_watch_says():
    from clpde.inpainting.navier_stokes import NavierStokesSolver
    from clpde.runtime import get_runtime

    truth = corpus.periodic(0, size=48)[None] / 255.0
    omega = np.zeros((48, 48), bool)
    omega[16:32, 16:32] = True
    seen = []

    def watch(iterations, image):
        seen.append(iterations)
        return len(seen) == 3  # the start, two checks

    solver = NavierStokesSolver(get_runtime(), truth, omega)
    solver.run(max_iter=1000, tol=0, mean_tol=0, check_every=5, watch=watch)
    assert seen == [0, 5, 10] and solver.iterations == 10 and not solver.converged
