"""Tiny calls of clpde's public functions that, together, launch its kernels: run on PoCL in
the test's own process and under Oclgrind in a child process (test_oclgrind.py,
benchmarks/portability.py).

As a program: ``python tests/portability/cases.py OUT NAME...`` runs the named cases (all
when none is named) on the default device and writes, in OUT, each case's arrays
(<name>.npz) and the kernels launched (kernels.json: "file:kernel" names).
Inputs are seeded and a few pixels across: Oclgrind interprets every instruction (and checks
every memory access), about 10^4 times slower than PoCL.
"""

from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import numpy as np


def _image(h=12, w=14, seed=1):
    return np.random.default_rng(seed).random((h, w)).astype(np.float32)


def _hole(shape, y0=4, y1=7, x0=5, x1=9):
    mask = np.zeros(shape, bool)
    mask[y0:y1, x0:x1] = True
    return mask


def _disc_frames(n=2, size=20, r=5):
    yy, xx = np.mgrid[:size, :size]
    return np.stack(
        [((yy - size // 2) ** 2 + (xx - 7 - k) ** 2 < r * r) * 0.7 + 0.15 for k in range(n)]
    ).astype(np.float32)


def _sphere(n=22, r=3.0):
    ax = np.arange(n) - (n - 1) / 2
    z, y, x = np.meshgrid(ax, ax, ax, indexing="ij")
    return np.sqrt(x**2 + y**2 + z**2) - r, z / n


def _diffuse():
    import clpde

    image = _image()
    out = {flow: clpde.diffuse(image, flow, steps=2) for flow in clpde.FLOWS}
    out["catte"] = clpde.diffuse(image, "perona-malik", steps=2, presmooth=1.0)
    return out


def _denoise():
    import clpde

    rgb = np.random.default_rng(2).random((10, 12, 3)).astype(np.float32)
    return {
        "grey": clpde.denoise_tv(_image(), 0.1, max_steps=4),
        "rgb": clpde.denoise_tv(rgb, 0.1, max_steps=4, channel_axis=-1),
        "gradient": clpde.denoise_tv(_image(), 0.1, max_steps=4, method="gradient"),
    }


def _inpaint(method, size=16, dtype=np.float32, **options):
    def run():
        import clpde

        image = _image(size, size).astype(dtype)
        if method == "exemplar":
            # a periodic texture: the hole's best patches match exactly, so the fill is the
            # same whichever of them a search finds first (PatchMatch's order follows the
            # launch geometry)
            yy, xx = np.mgrid[:size, :size]
            image = ((xx + 2 * yy) % 5 / 5).astype(np.float32)
        return {"out": clpde.inpaint(image, _hole(image.shape), method=method, **options)}

    return run


def _cpu_path(run):
    """run with the spectral kernel in its CPUs' shape (one item a block, candidates in
    vectors of 8), which the simulated device, a GPU, would not take by itself."""

    def cpu_run():
        from clpde.inpainting import spectral

        shape = spectral.work_shape
        spectral.work_shape = lambda runtime: (1, spectral.CPU_VECTOR)
        try:
            return run()
        finally:
            spectral.work_shape = shape

    return cpu_run


def _track(**options):
    def run():
        import clpde

        frames = _disc_frames()
        return {"masks": clpde.track(frames, frames[0] > 0.5, max_iterations=3, **options)}

    return run


def _track_colour(storage):
    # colour=True: the adaptive step's channels summed side by side (adaptive_betas)
    def run():
        import clpde

        grey = _disc_frames()
        frames = np.stack([grey, 1 - grey, 0.5 + 0.3 * grey], axis=-1)
        masks = clpde.track(frames, grey[0] > 0.5, max_iterations=3, colour=True, storage=storage)
        return {"masks": masks}

    return run


def _surface(storage):
    def run():
        from clpde.surface import ImplicitSurface

        phi, z = _sphere(n=18, r=2.0)
        s = ImplicitSurface(phi, 1.0, storage=storage)
        return {
            "heat": s.heat(z, 0.2),
            "tv": s.tv(z, 0.1),
            "denoise": s.denoise_tv(z, 0.05, t=0.1),
            "turk": s.reaction_diffusion(2),
            **{f"principal_{i}": a for i, a in enumerate(s.principal_directions())},
        }

    return run


def _track_region(storage):
    def run():
        import clpde

        phi, z = _sphere(n=28, r=4.0)  # tracking keeps 9 cells clear of the border
        frames = clpde.track_region(phi, z, beta=0.5, t=0.1, storage=storage, keep_volumes=True)
        return {"phihat": frames[-1].phihat, "phi": frames[-1].phi}

    return run


def _film():
    import clpde

    frames = np.repeat(_image(12, 12)[None], 3, 0)
    frames[1, 5:7, 5:7] = 1.0  # a blotch in the middle frame
    mask = clpde.detect_defects(frames)
    masks = np.zeros(frames.shape, bool)
    masks[1, 5:7, 5:7] = True
    return {"mask": mask, "filled": clpde.inpaint_video(frames, masks)}


# Every case runs whole under Oclgrind: its --quick (the first and last work-groups of
# each launch only) leaves results that later launches read half computed.
def _volumes():
    import clpde
    from clpde.volumes import inpaint_volume

    rng = np.random.default_rng(3)
    vol = rng.random((6, 10, 12)).astype(np.float32)
    mask = np.zeros(vol.shape, bool)
    mask[2:4, 4:7, 4:8] = mask[5, 1:3, 1:3] = True
    spacing = (2, 1, 1)
    out = {
        "tv": clpde.denoise_tv(vol, 0.1, spacing=spacing, max_steps=4),
        "tv_rgb": clpde.denoise_tv(
            np.stack([vol, vol[::-1]], -1), 0.1, channel_axis=-1, spacing=spacing, max_steps=4
        ),
        "catte": clpde.diffuse(vol, "perona-malik", steps=2, presmooth=1.0, spacing=spacing),
    }
    flows = ("heat", "tv", "curvature")
    out |= {flow: clpde.diffuse(vol, flow, steps=2, spacing=spacing) for flow in flows}
    for method in ("harmonic", "biharmonic", "spectral"):
        out[method] = inpaint_volume(vol, mask, spacing=spacing, method=method)
    return out


CASES = {
    "diffuse": _diffuse,
    "denoise": _denoise,
    "transport_step": _inpaint("transport", max_steps=4),
    "inpaint_coherence": _inpaint("coherence"),
    "inpaint_navier_stokes": _inpaint("navier-stokes", size=12, max_iter=1),
    "track_lists": _track(),
    "track_bricks": _track(storage="bricks8x8"),
    "track_ncc_contrast": _track(discrepancy="ncc", features="contrast"),
    "track_huber_edges": _track(discrepancy="huber", features="edges", storage="bricks8x8"),
    "track_region_term": _track(region_weight=1.0, storage="bricks16x4"),
    "track_colour_lists": _track_colour("lists"),
    "track_colour_bricks": _track_colour("bricks8x8"),
    "inpaint_spectral": _inpaint("spectral", iterations=8, shifts=1),
    "inpaint_spectral_f64": _inpaint("spectral", dtype=np.float64, iterations=4, shifts=1),
    "inpaint_spectral_cpu_path": _cpu_path(_inpaint("spectral", iterations=8, shifts=1)),
    "inpaint_exemplar": _inpaint("exemplar"),
    "surface_lists": _surface("lists"),
    "surface_bricks": _surface("bricks"),
    "track_region_lists": _track_region("lists"),
    "track_region_bricks": _track_region("bricks"),
    "film": _film,
    "volumes": _volumes,
}


def _record_launches(names: set) -> None:
    """Note every kernel a case fetches (its first launch follows)."""
    from clpde import runtime

    real_kernel, real_new = runtime.Runtime.kernel, runtime.Runtime.new_kernel

    def kernel(self, filename, name, *args, **kwargs):
        names.add(f"{filename}:{name}")
        return real_kernel(self, filename, name, *args, **kwargs)

    def new_kernel(self, filename, name, *args, **kwargs):
        names.add(f"{filename}:{name}")
        return real_new(self, filename, name, *args, **kwargs)

    runtime.Runtime.kernel, runtime.Runtime.new_kernel = kernel, new_kernel


def main(argv: list[str]) -> int:
    out = Path(argv[0])
    out.mkdir(parents=True, exist_ok=True)
    wanted = argv[1:] or list(CASES)
    launched: set[str] = set()
    _record_launches(launched)
    for name in wanted:
        t0 = time.perf_counter()
        arrays = CASES[name]()
        np.savez(out / f"{name}.npz", **{k: np.asarray(v) for k, v in arrays.items()})
        print(f"{name}: {time.perf_counter() - t0:.1f} s", flush=True)
    (out / "kernels.json").write_text(json.dumps(sorted(launched)))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
