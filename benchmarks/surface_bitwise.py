"""Results of every surface kernel family, saved for a bitwise check across a refactoring.

    PYTHONPATH=<tree A> python benchmarks/surface_bitwise.py save out/sbit/a
    PYTHONPATH=<tree B> python benchmarks/surface_bitwise.py save out/sbit/b
    python benchmarks/surface_bitwise.py compare out/sbit/a out/sbit/b

Small grids (a sphere at spacing 0.1, a torus at 0.1), float inputs: the band construction
and closest points (through every flow), the heat flow on lists and on bricks (plain,
weighted, not alternating), TV with a fixed and a dynamic lambda, harmonic maps (p = 1, 2,
line fields), colour denoising, diffusion along a field, principal directions, Turk's
reaction-diffusion (plain and along), extension by the PDE, reinitialisation, sampling
(tricubic and trilinear), trilinear surfaces, double precision and a surface from a mesh
(mesh_refine). kernels/surface.cl's split was checked with it.
"""

import warnings
from pathlib import Path

import numpy as np
from bitwise import main


def save(out: Path) -> None:
    import clpde
    from clpde.surface import ImplicitSurface

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    rng = np.random.default_rng(1)
    res = {}
    s = ImplicitSurface.sphere(1.0, spacing=0.1)
    u = rng.normal(size=s.shape)
    x, y, z = s.coordinates()
    res["heat"] = s.heat(u, 0.02)
    res["heat_weighted"] = s.heat(u, 0.02, weighted=True)
    res["heat_forward"] = s.heat(u, 0.02, alternate=False)
    s.storage = "bricks"
    res["heat_bricks"] = s.heat(u, 0.02)
    res["heat_bricks_weighted"] = s.heat(u, 0.02, weighted=True)
    res["heat_bricks_vector"] = s.heat(np.stack([u, -u]), 0.01)
    s.storage = "lists"
    res["tv"] = s.tv(u, 0.01)
    res["tv_lam"] = s.denoise_tv(u, lam=2.0, t=0.01)
    res["tv_sigma"] = s.denoise_tv(u, sigma=0.3, t=0.02)
    v = s.field(lambda x, y, z: [x + 0 * y, y + 0 * z, z + 0 * x])
    v /= np.sqrt((v**2).sum(0)) + 1e-12
    v[:, np.abs(s.psi) > 0.5] = 1 / np.sqrt(3)
    res["harmonic2"] = s.harmonic_map(v, 0.01, p=2)
    res["harmonic1"] = s.harmonic_map(v, 0.01, p=1)
    res["harmonic_line"] = s.harmonic_map(v, 0.01, p=2, line_field=True)
    rgb = np.abs(rng.normal(size=(3,) + s.shape))
    res["colour"] = s.denoise_colour(rgb, 0.005)
    major, minor, curv = s.principal_directions()
    res["major"], res["minor"], res["curv"] = major, minor, curv
    res["along"] = s.diffuse_along(u, major, 0.01)
    res["turk"] = s.reaction_diffusion(20)
    res["turk_along"] = s.reaction_diffusion(20, direction=major)
    res["extend_pde"] = s.extend(u, method="pde", iterations=10)
    res["extend_cp"] = s.extend(u)
    pts = rng.normal(size=(50, 3))
    pts /= np.linalg.norm(pts, axis=1, keepdims=True)
    res["sample_cubic"] = s.sample(u, pts)
    res["sample_linear"] = s.sample(u, pts, interpolation="trilinear")
    bumpy = ImplicitSurface.from_volume(
        s.psi * (1.3 + 0.2 * np.cos(3 * x)), 0.1, s.origin, reinitialize=True
    )
    res["reinit"] = bumpy.psi
    t = ImplicitSurface.torus(1.0, 0.4, spacing=0.1, interpolation="trilinear")
    res["torus_linear_heat"] = t.heat(rng.normal(size=t.shape), 0.02)
    d = ImplicitSurface.sphere(1.0, spacing=0.1, dtype=np.float64)
    res["heat_double"] = d.heat(u, 0.02)
    res["tv_double"] = d.denoise_tv(u, sigma=0.3, t=0.02)
    try:
        import trimesh

        m = ImplicitSurface.from_mesh(trimesh.creation.icosphere(2), resolution=24)
        res["mesh_psi"] = m.psi
    except ImportError:
        print("trimesh missing: no mesh case")
    for name, value in res.items():
        np.save(out / f"{name}.npy", np.asarray(value))


if __name__ == "__main__":
    main(save, __doc__)
