"""3D diffusion (clpde/volumes/flows.py): each kernel against the numpy reference of its
scheme, heat on a 3D Gaussian (second order, with thick slices too: a known answer in
physical units), and clpde.diffuse's dispatch and refusals."""

import numpy as np
import pytest

import clpde
from clpde.errors import DeviceMemoryError
from clpde.volumes.flows import gaussian_weights_1d, stability_limit_volume
from tests.reference import volumes as ref


def _unit(rng, shape):
    v = rng.random(shape)
    return (v - v.min()) / (v.max() - v.min())


H = (2.0, 1.0, 0.5)


@pytest.mark.parametrize(
    "flow,params",
    [
        ("heat", {}),
        ("perona-malik", {"kappa": 0.3}),
        ("perona-malik", {"kappa": 0.3, "edge": "rational"}),
        ("perona-malik", {"kappa": 0.3, "presmooth": 1.0}),
        ("tv", {"eps": 0.1}),
        ("curvature", {"eps": 1e-3}),
    ],
)
def test_kernels_match_the_reference(rng, flow, params):
    u0 = _unit(rng, (5, 6, 7, 2))
    steps = 4
    dt = 0.8 * stability_limit_volume(flow, H, params.get("eps", 0.005))
    out = clpde.diffuse(
        u0, flow, steps=steps, dt=dt, spacing=H, channel_axis=-1, dtype=np.float64, **params
    )
    u = np.moveaxis(u0, -1, 0)
    for _ in range(steps):
        if flow == "heat":
            u = ref.heat_step(u, dt, H)
        elif flow == "tv":
            u = ref.tv_step(u, dt, params["eps"], H)
        elif flow == "curvature":
            u = ref.curvature_step(u, dt, params["eps"], H)
        else:
            us = u
            if params.get("presmooth"):
                # presmooth / h voxels along each axis (z, y, x)
                us = ref.gauss(u, [gaussian_weights_1d(params["presmooth"] / hk) for hk in H])
            u = ref.pm_step(u, us, dt, params["kappa"], H, params.get("edge", "exp"))
    np.testing.assert_allclose(out, np.moveaxis(u, 0, -1), atol=1e-9)


def _heat_error(h, spacing, t_end=0.5, s0=1.0, half=6.0):
    """Largest error of the heat flow from a Gaussian of deviation s0 at time t_end, on a grid
    of spacing h * spacing over [-half, half]^3 (the exact answer: variance s0^2 + 2 t)."""
    sp = np.asarray(spacing, float) * h
    axes = [(np.arange(int(round(2 * half / s))) + 0.5) * s - half for s in sp]
    z, y, x = np.meshgrid(*axes, indexing="ij")
    r2 = x**2 + y**2 + z**2

    def gaussian(s2):
        return np.exp(-r2 / (2 * s2)) * (s0**2 / s2) ** 1.5

    steps = int(np.ceil(t_end / (0.8 * stability_limit_volume("heat", sp))))
    u = clpde.diffuse(
        gaussian(s0**2), "heat", steps=steps, dt=t_end / steps, spacing=sp, dtype=np.float64
    )
    return np.abs(u - gaussian(s0**2 + 2 * t_end)).max()


@pytest.mark.parametrize("spacing", [(1, 1, 1), (2, 1, 1)])
def test_heat_on_a_gaussian_is_second_order(spacing):
    coarse, fine = _heat_error(0.4, spacing), _heat_error(0.2, spacing)
    assert coarse < 0.01
    assert 3.0 < coarse / fine < 5.0


def test_thick_slices_diffuse_less_per_voxel_along_z(rng):
    """In physical units, a Gaussian spreads the same along every axis whatever the spacing:
    with slices twice as thick the z profile in voxels spreads half as far as the x one."""
    u0 = np.zeros((21, 21, 21))
    u0[10, 10, 10] = 1.0
    out = clpde.diffuse(u0, "heat", steps=40, spacing=(2, 1, 1), dtype=np.float64)
    pz, px = out[:, 10, 10], out[10, 10, :]
    var = lambda p: float((p * (np.arange(21) - 10) ** 2).sum() / p.sum())  # noqa: E731
    assert var(px) == pytest.approx(4 * var(pz), rel=0.05)


def test_perona_malik_keeps_an_edge_heat_blurs(rng):
    vol = np.zeros((12, 12, 12))
    vol[:, :, 6:] = 1.0
    noisy = vol + 0.05 * rng.standard_normal(vol.shape)
    pm = clpde.diffuse(noisy, "perona-malik", steps=30, kappa=0.1, presmooth=1.0)
    heat = clpde.diffuse(noisy, "heat", steps=30)
    edge = lambda v: float((v[:, :, 6] - v[:, :, 5]).mean())  # noqa: E731
    assert edge(pm) > 0.8 > edge(heat)
    assert pm[:, :, :4].std() < noisy[:, :, :4].std() / 2


def test_info_and_dtype(rng):
    vol = (rng.random((6, 7, 8)) * 255).astype(np.uint8)
    out, info = clpde.diffuse(vol, "tv", steps=3, spacing=(1, 1, 1), return_info=True)
    assert out.dtype == np.uint8 and out.shape == vol.shape
    assert info.steps == 3 and info.stability_limit == pytest.approx(0.005 / 6)


@pytest.mark.parametrize(
    "kwargs,match",
    [
        ({"flow": "curvature", "weight": 1}, "no parameter 'weight'"),
        ({"flow": "heat", "kappa": 1}, "no parameter 'kappa'"),
        ({"flow": "heat", "dt": 1.0}, "stability limit"),
        ({"flow": "perona-malik", "edge": "tukey"}, "edge"),
    ],
)
def test_bad_volume_flows_give_one_line(kwargs, match):
    with pytest.raises(clpde.InputError, match=match):
        clpde.diffuse(np.zeros((4, 5, 6)), **kwargs)


@pytest.mark.parametrize(
    "flow,params",
    [
        ("heat", {}),
        ("perona-malik", {"kappa": 0.3, "presmooth": 1.0}),
        ("tv", {"eps": 0.1}),
        ("curvature", {}),
    ],
)
def test_slabs_equal_the_whole_volume(rng, monkeypatch, flow, params):
    from clpde.volumes import flows

    u0 = _unit(rng, (23, 6, 7, 2))
    run = lambda: clpde.diffuse(  # noqa: E731
        u0, flow, steps=7, spacing=H, channel_axis=-1, dtype=np.float64, **params
    )
    whole = run()
    slabs = []
    real_run = flows._run
    monkeypatch.setattr(flows, "TILE_PLANES", 12)  # slabs of 12 planes with their ghosts
    monkeypatch.setattr(
        flows, "_run", lambda grid, *a: slabs.append(grid.shape) or real_run(grid, *a)
    )
    tiled = run()
    assert len(slabs) > 4 and max(s[1] for s in slabs) <= 12  # several slabs and rounds
    np.testing.assert_allclose(tiled, whole, atol=1e-12)
    assert np.abs(whole - u0).max() > 0.05  # the flow moved it


def test_too_few_planes_for_the_ghosts_are_refused(monkeypatch):
    from clpde.volumes import flows

    monkeypatch.setattr(flows, "TILE_PLANES", 2)
    with pytest.raises(DeviceMemoryError, match="crop the volume"):
        clpde.diffuse(np.random.default_rng(0).random((9, 5, 6)), "heat", steps=2)
