"""When to stop an evolution that starts from a smooth fill: the step at which it best
predicts a ring of known pixels hidden around the hole (held-out early stopping).

The transport (transport.py) and the Navier-Stokes vorticity transport (navier_stokes.py)
start from the biharmonic fill and evolve towards a steady state in which the Laplacian is
constant along the isophotes. That steady state is not the best estimate of the hole: on a
pattern that repeats at a scale below the hole's depth, the isophotes entering the hole are
continued with a phase nothing in the equation fixes, and the error grows with every step
from the start (periodic patterns: 20.6 dB at the start, 16.8 at the steady state); on
edges and smooth shading the same steps gain several dB. Which holds is a property of the
surround, not of the hole's size, so neither a step count nor a depth rule separates them
(docs/inpainting.md, "Stopping on a hidden ring").

The same evolution is run once more with a ring of known pixels around the hole hidden as
well; the step count at which it fills that ring best is where the real run stops. The ring
is `width` px wide, and only holes at least that deep are validated: a thinner hole grown by
the ring would be a problem of another kind (a 2 px scratch becomes a 10 px band), and thin
damage keeps the method's own stop.

The probe need not run to its own stop: once its ring error is RISE times the least so
far, that least is the choice (Tracker.risen), and it stops there.

The transport validates only boxes whose surround repeats (periodic_surround, its default
`holdout_where="periodic"`): on photos the ring, filled from the hole grown by it,
favoured the smooth start more often than the real hole did (docs/inpainting.md).
"""

from __future__ import annotations

import numpy as np
from scipy import ndimage

from .pick import periodic_clusters

WIDTH = 4  # px; 2 and 4 measured on the corpus's calibration half (docs/inpainting.md)
GAIN = 0.95  # an earlier state replaces the method's own stop where its ring error is below
# GAIN times the last state's: a few per cent is within what the ring's draw varies by
RISE = 1.2  # the probe stops once its ring error is RISE times its least so far: on the
# calibration half (442 boxes of both methods, extended seeds) no curve that rose more than
# 1.07 times came back to change the choice; 1.2 cuts 21-24 % of the probe's checks


def periodic_surround(data: np.ndarray, omega: np.ndarray) -> bool:
    """Whether a cluster of omega at least pick.MIN_RADIUS thick sits in a surround that
    repeats (pick.periodic_clusters, the default's test for the exemplar's clusters)."""
    return bool(periodic_clusters(data, omega).any())


def ring(omega: np.ndarray, width: int = WIDTH) -> np.ndarray | None:
    """The known pixels within `width` px (Euclidean) of omega, or None where the hole is
    thinner than `width` (its deepest pixel closer than `width` to a known one) or no such
    pixel is known."""
    if width <= 0 or not omega.any() or omega.all():
        return None
    if float(ndimage.distance_transform_edt(omega).max()) < width:
        return None
    band = (ndimage.distance_transform_edt(~omega) <= width) & ~omega
    return band if band.any() else None


class Tracker:
    """The squared error on the hidden ring of each state of a run; `best` is the step count
    of the first state with the least error."""

    def __init__(self, data: np.ndarray, band: np.ndarray):
        self.truth = np.asarray(data, np.float64)[:, band]
        self.band = band
        self.steps: list[int] = []
        self.errors: list[float] = []

    def add(self, steps: int, state: np.ndarray) -> None:
        d = np.asarray(state, np.float64)[:, self.band] - self.truth
        self.steps.append(int(steps))
        self.errors.append(float(np.mean(d * d)))

    def risen(self) -> bool:
        """Whether the last error is RISE times the least so far: the probe can stop, the
        choice is that least (a later state would have to fall below it again)."""
        return len(self.errors) > 1 and self.errors[-1] > RISE * min(self.errors)

    def best(self) -> int | None:
        """The step count with the least error, or None when that is the run's last state
        (the method's own stop stands: the run is left as it was)."""
        if not self.errors:
            return None
        i = int(np.argmin(self.errors))
        if i == len(self.errors) - 1 or self.errors[i] > GAIN * self.errors[-1]:
            return None
        return self.steps[i]
