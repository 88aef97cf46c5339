"""TV denoising's dynamic lambda (C.2) on a surface, kept on the device while the flow steps."""

from __future__ import annotations

import warnings

import numpy as np
import pyopencl.array as cla

# The kernels/ files this module's kernel lookups name (tests/core/test_kernel_names.py checks).
KERNEL_FILES = ("surface/flows.cl",)


class DynamicLambda:
    """lambda of (C.2) kept on the device: each update enqueues the surface integrals' per-cell
    terms (the flow's lambda_terms, in its storage), their chunk sums and the new lambda
    (flows_tv_lambda_update), with no read-back; the history of lambda comes back once, at the end.
    Its kernels come with the flow's defines (they read none of them): on the lists, no
    build of their own."""

    CHUNK = 2048

    def __init__(self, surf, flow, u0_dev, lam_dev, eps, sigma, lam_max, updates, correct=True):
        g, q = surf.grid, surf.runtime.queue
        self.defines = flow.defines
        self.surf, self.flow, self.u0, self.lam, self.eps = surf, flow, u0_dev, lam_dev, eps
        self.sigma, self.lam_max, self.correct = sigma, lam_max, correct
        self.n = flow.terms_size
        # zeros: the bricks' terms are written at the nodes only
        self.terms = [cla.zeros(q, self.n, g.dtype) for _ in range(3)]
        self.groups = max(1, -(-self.n // self.CHUNK))
        self.partials = [cla.empty(q, self.groups, g.dtype) for _ in range(3)]
        self.slots = cla.zeros(q, max(updates, 1), g.dtype)
        self.capped = cla.zeros(q, 1, np.int32)
        self.state = cla.to_device(q, np.ones(1, g.dtype))  # the correction factor f
        self._chunk_sum = g.kernel("surface/flows.cl", "flows_chunk_sum", **self.defines)
        self._update = g.kernel("surface/flows.cl", "flows_tv_lambda_update", **self.defines)

    def _sums(self, sides: int) -> None:
        s = self.surf
        q = s.runtime.queue
        self.flow.lambda_terms(self.u0, self.terms, sides, self.eps)
        for a, partial in zip(self.terms, self.partials, strict=True):
            self._chunk_sum(
                q,
                *s.runtime.items(self.groups),
                a.data,
                np.int32(self.n),
                np.int32(self.CHUNK),
                partial.data,
            )

    def update(self, sides: int, slot: int) -> None:
        s = self.surf
        g, q = s.grid, s.runtime.queue
        self._sums(sides)
        self._update(
            q,
            (1,),
            (1,),
            *(p.data for p in self.partials),
            np.int32(self.groups),
            g.scalar(1 / (s.spacing * self.sigma**2)),
            g.scalar(self.correct / self.sigma**2),
            g.scalar(self.lam_max),
            self.lam.data,
            self.state.data,
            self.slots.data,
            np.int32(slot),
            self.capped.data,
        )

    def history(self) -> list[float]:
        if self.capped.get()[0]:
            warnings.warn(
                f"the dynamic lambda was capped at {self.lam_max:g}, the largest this time step "
                "keeps stable; pass a smaller dt (or leave dt=None) to let it grow further",
                stacklevel=4,
            )
        return [float(v) for v in self.slots.get()]

    def residual_variance(self) -> float:
        """Mean of (u - u0)^2 over the surface (smeared-delta quadrature) for the flow's
        current state (forward differences)."""
        self._sums(0)
        _, area, resid = (float(p.get().astype(np.float64).sum()) for p in self.partials)
        return resid / area
