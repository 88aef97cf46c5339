"""The flows on a surface as ImplicitSurface's methods: their one public home.

`FlowMethods` is a base of ImplicitSurface, kept here so that implicit.py holds the
surface's state (psi, bands, data on the band) and this file the documented entry points of
the flows (shape_methods.py has the curvature directions and pictures). Each method checks
nothing itself and calls its implementation: flows.py (heat, tv, denoise_tv, diffuse_along,
stability_limit), harmonic.py (harmonic_map, denoise_colour), textures.py
(reaction_diffusion).
"""

from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike

from . import flows as _flows
from . import harmonic as _harmonic
from . import textures as _textures
from .flows import SurfaceDenoiseInfo


class FlowMethods:
    """The flows of ImplicitSurface (its base class)."""

    def stability_limit(self, flow: str = "heat", eps: float = 1.0, lam: float = 0.0) -> float:
        """Largest stable explicit time step (world time units) of a flow on this surface.

        Parameters
        ----------
        flow : {'heat', 'tv', 'harmonic2', 'harmonic1', 'along'}
            The flow.
        eps : float, optional
            The regularisation of |grad u| of 'tv' and 'harmonic1'.
        lam : float, optional
            The fidelity weight of a TV denoising step.

        Returns
        -------
        float
            The largest stable dt (the grid spacing sets it).

        Raises
        ------
        InputError
            For an unknown flow.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> round(s.stability_limit("heat"), 6)
        0.001667
        """
        return _flows.stability_limit(self, flow, eps, lam)

    def heat(
        self,
        u: ArrayLike,
        t: float,
        dt: float | None = None,
        *,
        weighted: bool = False,
        alternate: bool = True,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Intrinsic heat flow on the surface for time t: eq. (4.8), or (4.7) with weighted=True.

        Appendix E's scheme (one-sided gradient, projection on the tangent plane with N from
        central differences of psi, the complementary one-sided divergence), explicit Euler
        steps, whole-band closest-point re-extension after each step.

        Parameters
        ----------
        u : array_like
            Data on the surface: dense (`shape`, or (channels,) + `shape`) or in band form
            (`band_indices`); returned in kind.
        t : float
            The evolution time (world units).
        dt : float, optional
            The time step; 0.8 of `stability_limit` by default, never beyond it.
        weighted : bool, optional
            Eq. (4.7), the flux weighted by |grad psi|, instead of (4.8).
        alternate : bool, optional
            Cycle the step through the eight forward/backward combinations, as appendix E
            suggests (smaller errors, docs/surface.md); False keeps forward gradient /
            backward divergence throughout.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.

        Returns
        -------
        ndarray
            u after time t, in u's form and float dtype.

        Raises
        ------
        InputError
            For data of another shape, non-finite values in the band or an unstable dt.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> u = s.field(lambda x, y, z: z)
        >>> smooth = s.heat(u, 0.05)
        >>> smooth.shape == u.shape, smooth.dtype
        (True, dtype('float64'))
        """
        return _flows.heat(
            self, u, t, dt, weighted=weighted, alternate=alternate, progress=progress
        )

    def tv(
        self,
        u: ArrayLike,
        t: float,
        dt: float | None = None,
        *,
        eps: float = 1.0,
        weighted: bool = False,
        alternate: bool = True,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Intrinsic anisotropic (total variation) flow (4.10) for time t.

        Parameters
        ----------
        u : array_like
            Data on the surface, dense or in band form (as for `heat`); returned in kind.
        t : float
            The evolution time.
        dt : float, optional
            The time step; 0.8 of `stability_limit` by default.
        eps : float, optional
            Regularisation of |P grad u| (world gradient units), so that the explicit step
            stays bounded (dt <= h^2 eps / 6).
        weighted : bool, optional
            The flux weighted by |grad psi|, as for `heat`.
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.

        Returns
        -------
        ndarray
            u after time t, in u's form.

        Raises
        ------
        InputError
            For data of another shape, non-finite values in the band or an unstable dt.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> s.tv(s.field(lambda x, y, z: z), 0.01).shape == s.shape
        True
        """
        return _flows.tv(
            self,
            u,
            t,
            dt,
            eps=eps,
            weighted=weighted,
            alternate=alternate,
            progress=progress,
        )

    def denoise_tv(
        self,
        u: ArrayLike,
        sigma: float | None = None,
        t: float = 1.0,
        dt: float | None = None,
        *,
        lam: float | None = None,
        eps: float = 1.0,
        alternate: bool = True,
        correct_lambda: bool = True,
        progress: bool | None = None,
        return_info: bool = False,
    ) -> np.ndarray | tuple[np.ndarray, SurfaceDenoiseInfo]:
        """TV denoising on the surface with a fidelity term (C.1).

        Parameters
        ----------
        u : array_like
            Noisy data on the surface, dense or in band form (as for `heat`).
        sigma : float, optional
            The noise level, for the dynamic lambda of (C.2): updated on the device every 10
            steps, never read back while stepping, capped (with a warning) where it would
            make dt unstable. Give it or `lam`.
        t : float, optional
            The evolution time.
        dt : float, optional
            The time step; 0.8 of `stability_limit` by default.
        lam : float, optional
            A fixed fidelity weight instead of `sigma`.
        eps : float, optional
            Regularisation of |P grad u|, as for `tv`.
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        correct_lambda : bool, optional
            Scale the dynamic lambda by a factor that moves until the residual variance is
            sigma^2, the constraint (C.2) comes from (the discrete (C.2) alone settles above
            it, docs/surface.md); False is the plain formula (kernels/surface/flows.cl,
            flows_tv_lambda_update).
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.
        return_info : bool, optional
            Also return a SurfaceDenoiseInfo: steps, dt, the lambda history and the residual
            variance (mean of (u - u0)^2 over the surface).

        Returns
        -------
        ndarray or (ndarray, SurfaceDenoiseInfo)
            The denoised data in u's form (and the info with return_info).

        Raises
        ------
        InputError
            Unless exactly one of sigma and lam is given; for data that cannot be used.

        Examples
        --------
        >>> import numpy as np
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> noise = 0.1 * np.random.default_rng(0).normal(size=s.shape)
        >>> noisy = s.field(lambda x, y, z: z) + noise
        >>> clean, info = s.denoise_tv(noisy, sigma=0.1, t=0.01, return_info=True)
        >>> clean.shape == s.shape, info.steps > 0
        (True, True)
        """
        return _flows.denoise_tv(
            self,
            u,
            sigma,
            t,
            dt,
            lam=lam,
            eps=eps,
            alternate=alternate,
            correct_lambda=correct_lambda,
            progress=progress,
            return_info=return_info,
        )

    def diffuse_along(
        self,
        u: ArrayLike,
        direction: ArrayLike,
        t: float,
        dt: float | None = None,
        *,
        alternate: bool = True,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Anisotropic diffusion along a tangent field (4.15): a flow visualisation of the
        field when u is noise.

        Parameters
        ----------
        u : array_like
            Data on the surface, dense or in band form (as for `heat`); returned in kind.
        direction : array_like
            (3, nz, ny, nx) tangent field d along which u diffuses; normalised here (zero
            vectors stay zero, and u does not diffuse there).
        t : float
            The evolution time (world units).
        dt : float, optional
            The time step; 0.8 of `stability_limit` ('along') by default.
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.

        Returns
        -------
        ndarray
            u after time t, in u's form and float dtype.

        Raises
        ------
        InputError
            For a direction or data of another shape, non-finite values in the band or an
            unstable dt.

        Examples
        --------
        >>> import numpy as np
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.2)
        >>> x, y, z = s.coordinates()
        >>> parallels = np.stack(np.broadcast_arrays(-y, x, 0 * z))
        >>> noise = np.random.default_rng(0).uniform(size=s.shape)
        >>> s.diffuse_along(noise, parallels, 0.01).shape == s.shape
        True
        """
        return _flows.diffuse_along(
            self, u, direction, t, dt, alternate=alternate, progress=progress
        )

    def harmonic_map(
        self,
        u: ArrayLike,
        t: float,
        p: int = 2,
        dt: float | None = None,
        *,
        eps: float = 1.0,
        alternate: bool = True,
        progress: bool | None = None,
        line_field: bool = False,
    ) -> np.ndarray:
        """Harmonic map flow of unit vectors on the surface: (D.7) for p = 2, (4.11) for p = 1.

        The vectors are renormalised after every step, so they stay unit vectors.

        Parameters
        ----------
        u : array_like
            Unit vectors on the surface: (channels, nz, ny, nx), or their band form
            (channels, n) (`band_indices`); returned in kind. Vectors off unit length are
            normalised, with a warning.
        t : float
            The evolution time (world units).
        p : {1, 2}, optional
            The exponent: 2 smooths as the heat flow does, 1 (the TV analogue) keeps edges.
        dt : float, optional
            The time step; 0.8 of `stability_limit` ('harmonic2' or 'harmonic1') by default.
        eps : float, optional
            Regularisation of the gradient's norm for p = 1, as for `tv`.
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.
        line_field : bool, optional
            Treat u as a field of lines, u and -u alike (principal directions, Figure 4.5):
            before a step or an interpolation weighs neighbouring vectors, each is turned to
            the side of the vector it is compared with, so arbitrary sign flips between
            neighbours are neither smoothed into zero vectors nor counted as edges. This is
            the harmonic map into the projective plane, worked in local sign-aligned charts
            (the doubled-angle alternative needs a tangent frame, which has no smooth global
            choice on a sphere). The result's signs are arbitrary, consistent only locally.

        Returns
        -------
        ndarray
            The unit vectors after time t, in u's form.

        Raises
        ------
        InputError
            For p other than 1 or 2, data that is not vector data on the surface's grid or
            band, zero vectors in the band, or an unstable dt.

        Examples
        --------
        >>> import numpy as np
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.2)
        >>> v = s.field(lambda x, y, z: (np.ones_like(x), 0.1 * y, 0.1 * z))
        >>> v /= np.sqrt((v**2).sum(axis=0))
        >>> w = s.harmonic_map(v, 0.01)
        >>> w.shape == v.shape
        True
        >>> band = np.abs(s.psi) < 0.1
        >>> bool(np.allclose((w**2).sum(axis=0)[band], 1.0, atol=1e-5))   # still unit vectors
        True
        """
        return _harmonic.harmonic_map(
            self,
            u,
            t,
            p,
            dt,
            eps=eps,
            alternate=alternate,
            progress=progress,
            line_field=line_field,
        )

    def denoise_colour(
        self,
        rgb: ArrayLike,
        t: float,
        dt: float | None = None,
        *,
        brightness: str | None = "tv",
        p: int = 1,
        eps: float = 1.0,
        alternate: bool = True,
        progress: bool | None = None,
    ) -> np.ndarray:
        """Colour data on the surface denoised as in Figure 4.6: chroma and brightness apart.

        The chroma (the RGB vector over its length, a unit vector) follows the harmonic map
        flow of exponent p, the brightness (the length) a scalar flow, both for time t. Cells
        with no colour (black) take the grey chroma, so they carry no direction.

        Parameters
        ----------
        rgb : array_like
            (3, nz, ny, nx) colours, non-negative (e.g. in [0, 1]).
        t : float
            The evolution time of both flows (world units).
        dt : float, optional
            The time step; 0.8 of each flow's `stability_limit` by default.
        brightness : {'tv', 'heat', None}, optional
            The brightness's flow: 'tv' (4.10, the default: it keeps edges of brightness that
            heat blurs), 'heat' (4.8), or None to keep it.
        p : {1, 2}, optional
            The chroma's harmonic map exponent (1: (4.11), which keeps colour edges).
        eps : float, optional
            Regularisation of the gradient's norm of the p = 1 and TV flows.
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.

        Returns
        -------
        ndarray
            The denoised (3, nz, ny, nx) colours, in rgb's float dtype (float64 for
            integers).

        Raises
        ------
        InputError
            For data of another shape, non-finite or negative values on the band, an unknown
            brightness flow or an unstable dt.

        Examples
        --------
        >>> from clpde.surface import ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.2)
        >>> rgb = s.field(lambda x, y, z: (0.5 + 0.4 * x, 0.5 + 0.0 * y, 0.5 - 0.4 * z))
        >>> out = s.denoise_colour(rgb, 0.01)
        >>> out.shape == rgb.shape, out.dtype
        (True, dtype('float64'))
        """
        return _harmonic.denoise_colour(
            self,
            rgb,
            t,
            dt,
            brightness=brightness,
            p=p,
            eps=eps,
            alternate=alternate,
            progress=progress,
        )

    def reaction_diffusion(
        self,
        iterations: int,
        *,
        direction: ArrayLike | None = None,
        dt: float | None = None,
        seed: int = 0,
        params: dict | None = None,
        alternate: bool = True,
        progress: bool | None = None,
        state: ArrayLike | None = None,
    ) -> np.ndarray:
        """Turk's two-chemical reaction-diffusion on the surface: (4.12, 4.13), or (4.14)
        along a tangent field.

        It runs in grid units, as Turk's own code: dt per iteration, diffusion rates in
        cells^2 per unit time, so that patterns have the same size in cells on any surface.
        Turk's own rates (TURK) sit at the edge of the Turing instability (at beta = 12 the
        fastest mode's growth rate is 0): only the random spread of beta grows a pattern, and
        the anisotropic flow (4.14) along a tube's short circles, where few wavelengths fit,
        stays flat with them. docs/surface.md has the wavelengths measured with both sets of
        rates.

        Parameters
        ----------
        iterations : int
            The number of time steps.
        direction : array_like, optional
            (3, nz, ny, nx) tangent field for the anisotropic flow (4.14); normalised here.
        dt : float, optional
            The time step in grid time units; by default 0.9 of the stability limit, at
            most 1.
        seed : int, optional
            The seed of beta's random spread.
        params : dict, optional
            The rates: keys da, db (diffusion rates of a and b), s, beta, beta_spread and
            start (the chemicals' uniform start). Default: Figure 4.7's numbers
            (THESIS_FIG_4_7: D1 = 1, D2 = 1/16, s = 0.025); TURK gives Turk's own (1/8,
            1/32, s = 0.2/16, dt = 1).
        alternate : bool, optional
            Cycle the one-sided differences, as for `heat`.
        progress : bool, optional
            Draw a progress bar; by default only for long runs on a terminal.
        state : array_like, optional
            (2, nz, ny, nx) chemicals to continue from (a result of an earlier call); by
            default both start at params['start'].

        Returns
        -------
        ndarray
            The (2, nz, ny, nx) chemicals (a, b) after the iterations.

        Raises
        ------
        InputError
            For a direction of another shape or an unstable dt.

        Examples
        --------
        >>> from clpde.surface import TURK, ImplicitSurface
        >>> s = ImplicitSurface.sphere(1.0, spacing=0.1)
        >>> ab = s.reaction_diffusion(20, params=TURK)
        >>> ab.shape
        (2, 37, 37, 37)
        >>> more = s.reaction_diffusion(20, params=TURK, state=ab)   # 20 more iterations
        """
        return _textures.reaction_diffusion(
            self,
            iterations,
            direction=direction,
            dt=dt,
            seed=seed,
            params=params,
            alternate=alternate,
            progress=progress,
            state=state,
        )
