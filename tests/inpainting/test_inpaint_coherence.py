"""Coherence transport (clpde.inpainting.coherence) against the NumPy reference of the same
shell-by-shell formula, and its mathematics: oblique edges are continued across a slot,
colour shares one structure tensor, kappa = 0 is the isotropic mean."""

import numpy as np
import pytest

from clpde.errors import InputError
from clpde.inpainting import coherence, poisson
from tests.reference import inpainting_methods as ref


def _case(kind, seed=0, shape=(30, 36)):
    rng = np.random.default_rng(seed)
    ny, nx = shape
    y, x = np.mgrid[0:ny, 0:nx]
    if kind == "random":
        data = rng.random((3, ny, nx))
    else:
        s = np.cos(np.radians(35)) * x + np.sin(np.radians(35)) * y
        data = np.stack([0.5 + 0.4 * np.tanh((s - 20) / 1.2), 0.5 + 0.4 * np.sin(s / 3)])
    omega = np.zeros(shape, bool)
    omega[:, 15:21] = True  # a slot through the whole image: touches two borders
    omega[2:5, 2:10] = True
    omega[24:28, 27:33] = True
    return data, omega


@pytest.mark.parametrize("kind", ["random", "structured"])
@pytest.mark.parametrize("params", [{}, {"kappa": 0.0}, {"epsilon": 3.0, "sigma": 1.0, "rho": 2.5}])
def test_matches_reference(runtime, kind, params):
    data, omega = _case(kind)
    got = coherence.transport(data, omega, runtime, **params)
    want = ref.coherence_transport(data, omega, **params)
    np.testing.assert_allclose(got, want, atol=1e-5)
    assert np.array_equal(got[:, ~omega], data[:, ~omega])


def edge(angle, size=64, slot=8):
    """A smooth step whose normal makes `angle` degrees with x, a vertical slot across it."""
    y, x = np.mgrid[0:size, 0:size].astype(float)
    a = np.radians(angle)
    s = (x - size / 2) * np.cos(a) + (y - size / 2) * np.sin(a)
    image = 0.2 + 0.6 / (1 + np.exp(-s / 0.7))
    mask = np.zeros((size, size), bool)
    mask[:, size // 2 - slot // 2 : size // 2 + slot // 2] = True
    return image[None], mask


@pytest.mark.parametrize("angle", [30, 60])
def test_oblique_edge_is_continued(runtime, angle):
    # Measured: mean |error| in the slot 0.013 (30 deg) and 0.002 (60 deg), against 0.021
    # and 0.008 for the biharmonic fill, which smears the edge.
    image, mask = edge(angle)
    got = coherence.solve(image, mask, runtime)
    err = np.abs(got - image)[:, mask].mean()
    smooth = np.abs(poisson.solve(image, mask, runtime) - image)[:, mask].mean()
    assert err < 0.02 and err < 0.75 * smooth


def test_channel_order_does_not_matter(runtime):
    data, omega = _case("random", seed=3)
    got = coherence.transport(data, omega, runtime)
    perm = [2, 0, 1]
    swapped = coherence.transport(data[perm], omega, runtime)
    np.testing.assert_allclose(swapped, got[perm], atol=1e-6)


def test_kappa_zero_is_isotropic_mean(runtime):
    # One shell: each pixel of a one-pixel scratch is the 1/|y - x| weighted mean of the
    # known pixels in its disc.
    rng = np.random.default_rng(4)
    data = rng.random((1, 20, 20))
    omega = np.zeros((20, 20), bool)
    omega[10, 4:16] = True
    got = coherence.transport(data, omega, runtime, kappa=0.0, epsilon=3.0)
    y, x = 10, 8
    num = den = 0.0
    for dy in range(-3, 4):
        for dx in range(-3, 4):
            d2 = dx * dx + dy * dy
            if 0 < d2 <= 9 and not omega[y + dy, x + dx]:
                num += data[0, y + dy, x + dx] / np.sqrt(d2)
                den += 1 / np.sqrt(d2)
    assert got[0, y, x] == pytest.approx(num / den, abs=1e-6)


def test_bad_parameters(runtime):
    data, omega = _case("random")
    with pytest.raises(InputError, match="epsilon"):
        coherence.solve(data, omega, runtime, epsilon=1.0)
    with pytest.raises(InputError, match="kappa"):
        coherence.solve(data, omega, runtime, kappa=-1)


def test_margin_covers_what_it_reads(runtime):
    # the registry's MARGIN(omega, **params): a box of that margin gives the whole-image result
    data, omega = _case("structured", shape=(60, 70))
    omega[:] = False
    omega[25:35, 30:38] = True
    m = coherence.MARGIN(omega, epsilon=4.0, rho=3.0)
    assert m == coherence.margin(4.0, 1.4, 3.0) == 4 + 5 + 9 + 1
    whole = coherence.transport(data, omega, runtime, epsilon=4.0, rho=3.0)
    rows, cols = slice(25 - m, 35 + m), slice(30 - m, 38 + m)
    boxed = coherence.transport(
        data[:, rows, cols], omega[rows, cols], runtime, epsilon=4.0, rho=3.0
    )
    np.testing.assert_allclose(boxed, whole[:, rows, cols], atol=1e-6)


def test_double_precision_equals_reference(runtime):
    if not runtime.fp64:
        pytest.skip("the device has no double precision")
    data, omega = _case("structured")
    got = coherence.transport(data, omega, runtime, dtype=np.float64)
    np.testing.assert_allclose(got, ref.coherence_transport(data, omega), atol=1e-12)


def test_shells_equal_the_distance_transform():
    rng = np.random.default_rng(7)
    omega = rng.random((60, 70)) < 0.3
    omega[10:40, 10:40] = True  # thicker than the shifted masks' reach: the fallback
    for mask in (omega, omega & ~np.pad(np.ones((20, 30), bool), ((10, 30), (10, 30)))):
        np.testing.assert_array_equal(coherence.shells(mask), ref.coherence_shells(mask))
    thin = np.zeros((30, 30), bool)
    thin[5:8, :] = True
    np.testing.assert_array_equal(coherence.shells(thin), ref.coherence_shells(thin))
