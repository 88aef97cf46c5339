"""Results of the flows whose kernels a refactoring touched, saved for a bitwise check.

    PYTHONPATH=<tree A> python benchmarks/bitwise_check.py save out/bitwise/a
    PYTHONPATH=<tree B> python benchmarks/bitwise_check.py save out/bitwise/b
    python benchmarks/bitwise_check.py compare out/bitwise/a out/bitwise/b

Float inputs, so no rounding to uint8 hides a difference: inpainting by transport (both
stencils, the quartic root, both rotations, a soft mask, double precision, damage on the
border for the ghost kernels), Navier-Stokes and coherence inpainting (the CG sums), heat and
TV with the dynamic lambda on a sphere (the chunk sums). The kernels' move into
folders was checked with it.
"""

import warnings
from pathlib import Path

import numpy as np
from bitwise import main


def save(out: Path) -> None:
    import clpde
    from clpde.data import damaged_astronaut
    from clpde.surface import ImplicitSurface

    warnings.simplefilter("ignore")
    out.mkdir(parents=True, exist_ok=True)
    print("saving results of", clpde.__file__)
    _, dam, mask = damaged_astronaut()
    img, m = dam[100:228, 150:278].astype(np.float32) / 255, mask[100:228, 150:278].copy()
    m[:6, 20:40] = True  # damage touching the border: ghost kernels run
    soft = m.astype(np.float32) * 0.7  # a soft mask: the fidelity kernel runs
    soft[m & (np.arange(128)[None, :] % 3 == 0)] = 1.0
    cases = {
        "transport_central": dict(),
        "transport_isotropic_quartic": dict(stencil="isotropic", scaling="quartic-root"),
        "transport_cw_mean_fill": dict(rotation="cw", fill="mean"),
        "transport_double": dict(dtype=np.float64),
    }
    for name, kw in cases.items():
        r = clpde.inpaint(img, m, channel_axis=-1, method="transport", max_steps=60, **kw)
        np.save(out / f"{name}.npy", r)
    r = clpde.inpaint(img, soft, channel_axis=-1, method="transport", max_steps=60)
    np.save(out / "transport_soft.npy", r)
    for meth in ("navier-stokes", "coherence"):
        r = clpde.inpaint(img, m, channel_axis=-1, method=meth)
        np.save(out / f"{meth}.npy", r)
    s = ImplicitSurface.sphere(1.0, spacing=0.1)
    rng = np.random.default_rng(1)
    u = rng.normal(size=s.shape)
    np.save(out / "sphere_heat.npy", s.heat(u, 0.02))
    res = s.denoise_tv(u, sigma=0.3, t=0.02)
    np.save(out / "sphere_tv_sigma.npy", res[0] if isinstance(res, tuple) else res)


if __name__ == "__main__":
    main(save, __doc__)
