"""Thesis Figures 4.3-4.8 on generated shapes (or on your own mesh): PDEs intrinsic to an
implicit surface, computed on a narrow band of a 3D grid.

    python examples/surface_figures.py [--mesh FILE] [--resolution 64] [--out out/ | --docs]
                                       [--figures 4.3,4.4,4.5,4.6,4.7,4.8]

Writes surface_fig4_3.png (heat flow), surface_fig4_4.png (noisy / TV denoising with dynamic
lambda / TV flow without fidelity), surface_fig4_5.png (the major principal direction of a
bumpy surface, shown by noise diffused along it, before and after its regularisation as a
line field by the p = 1 harmonic map), surface_fig4_6.png (colour denoising: chroma by the
p = 1 harmonic map, brightness by TV flow), surface_fig4_7.png (Turk's reaction-diffusion with
Figure 4.7's numbers, isotropic and along the major principal direction) and
surface_fig4_8.png (noise diffused along the major and the minor principal direction).
"""

import argparse
import time

import numpy as np
from _output import add_output_arguments, output_folder

from clpde.surface import (
    ImplicitSurface,
    checker,
    colour_pattern,
    render_mesh,
    surface_noise,
)
from clpde.surface.runs import load_surface, tv_time, write_png


def picture(surf, u, size, view=(35.0, 30.0), vmin=None, vmax=None):
    return render_mesh(surf.to_mesh(u, vmin=vmin, vmax=vmax), size, *view)


def save(path, panels):
    write_png(str(path), np.concatenate(panels, axis=1))
    print(f"wrote {path}")


def main():
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--mesh", default=None, help="a mesh file (default: generated shapes)")
    parser.add_argument("--resolution", type=int, default=64)
    parser.add_argument("--size", type=int, default=260, help="pixels per panel")
    parser.add_argument("--iterations", type=int, default=4000, help="reaction-diffusion")
    add_output_arguments(parser)
    parser.add_argument("--figures", default="4.3,4.4,4.5,4.6,4.7,4.8", help="which figures")
    args = parser.parse_args()
    wanted = set(args.figures.split(","))
    out = output_folder(parser, args)
    rng = np.random.default_rng(0)
    torus = load_surface(args.mesh or "torus", args.resolution)
    genus2 = load_surface(args.mesh or "double-torus", int(args.resolution * 1.4))
    size = args.size
    h = torus.spacing

    start = time.perf_counter()
    if "4.5" in wanted:
        figure_4_5(args, out, rng)
    if "4.3" in wanted:
        u = checker(torus)
        panels = [picture(torus, u, size, vmin=0, vmax=1)]
        for t in (20 * h**2 / 6, 80 * h**2 / 6):  # 20 and 80 steps at the stability limit
            panels.append(picture(torus, torus.heat(u, t=t), size, vmin=0, vmax=1))
        save(out / "surface_fig4_3.png", panels)

    if "4.4" in wanted:
        sigma = 0.2
        noisy = checker(torus) + surface_noise(torus, sigma, np.random.default_rng(4))
        denoised, info = torus.denoise_tv(noisy, sigma=sigma, t=40 * h**2, return_info=True)
        print(
            f"  TV denoising: residual variance {info.residual_variance:.4f}, "
            f"sigma^2 = {sigma**2:.4f}"
        )
        flowed = torus.tv(noisy, t=tv_time(sigma, h))  # flattens the noise, keeps the squares
        save(
            out / "surface_fig4_4.png",
            [picture(torus, x, size, vmin=0, vmax=1) for x in (noisy, denoised, flowed)],
        )

    if "4.6" in wanted:
        clean = colour_pattern(torus)
        noise = surface_noise(torus, 0.25, np.random.default_rng(6), channels=3)
        noisy = np.clip(clean + noise, 0.01, 1)
        restored = torus.denoise_colour(noisy, t=4 * h**2)
        save(
            out / "surface_fig4_6.png", [picture(torus, x, size) for x in (clean, noisy, restored)]
        )

    if wanted & {"4.7", "4.8"}:
        major, minor, _ = genus2.principal_directions()
    if "4.7" in wanted:
        spots = genus2.reaction_diffusion(args.iterations, seed=1)[0]
        stripes = genus2.reaction_diffusion(args.iterations, direction=major, seed=1)[0]
        save(
            out / "surface_fig4_7.png",
            [picture(genus2, x, size, view=(20, 40)) for x in (spots, stripes)],
        )

    if "4.8" in wanted:
        noise = genus2.field(lambda x, y, z: 0 * x) + np.random.default_rng(8).random(genus2.shape)
        g = genus2.spacing
        panels = [
            picture(genus2, genus2.diffuse_along(noise, d, t=4 * g**2), size, view=(20, 40))
            for d in (major, minor)
        ]
        save(out / "surface_fig4_8.png", panels)
    print(f"all figures in {time.perf_counter() - start:.0f} s")


def bumpy_torus(resolution):
    """A torus with small bumps: its principal directions turn irregularly, as on a scanned
    mesh (the thesis uses a bunny)."""
    torus = load_surface("torus", resolution)
    x, y, z = torus.coordinates()
    k = 2 * np.pi / 0.35
    bumps = 0.012 * np.sin(k * x + 1) * np.sin(k * y) * np.sin(k * z + 2)
    psi = np.broadcast_to(torus.psi + bumps, torus.shape)
    return ImplicitSurface.from_volume(psi, torus.spacing, torus.origin)


def figure_4_5(args, out, rng):
    """Major principal direction before / after regularisation as a line field (its sign
    is arbitrary), each shown by noise diffused along it (as Figure 4.8 does)."""
    surf = load_surface(args.mesh, args.resolution) if args.mesh else bumpy_torus(args.resolution)
    h = surf.spacing
    major, _, _ = surf.principal_directions()
    smooth = surf.harmonic_map(major, t=4 * h, p=1, line_field=True)
    noise = surf.field(lambda x, y, z: 0 * x) + rng.random(surf.shape)
    panels = [
        picture(surf, surf.diffuse_along(noise, d, t=10 * h**2), args.size) for d in (major, smooth)
    ]
    save(out / "surface_fig4_5.png", panels)


if __name__ == "__main__":
    main()
