"""Parts that move otherwise than the whole object (issue 35, trackfoot): a walker's leg
swings ahead of the body that the object's motion carries; where the appearance clearly
says object next to the prediction, the prediction grows by that piece."""

import numpy as np

from clpde.tracking.parts import PART_FAR, PART_REACH, grow_parts


def _scene():
    """A predicted body (a disc) and evidence (log odds of the surroundings): the body
    and a 5 px wide leg reaching 10 px out of it clearly the object, a 1 px rim around
    the body and a blob 6 px off it too, everything else the surroundings."""
    yy, xx = np.mgrid[:80, :80]
    body = np.hypot(yy - 30, xx - 40) < 12
    leg = (np.abs(xx - 40) <= 2) & (yy >= 38) & (yy < 52)
    rim = (np.hypot(yy - 30, xx - 40) < 13) & ~body
    blob = np.hypot(yy - 30, xx - 62) < 3
    evidence = np.full(body.shape, 3.0)
    evidence[body | leg | rim | blob] = -3.0
    return body, leg, rim, blob, evidence


def test_a_leg_out_of_the_prediction_is_taken():
    body, leg, rim, blob, evidence = _scene()
    grown = grow_parts(body, evidence)
    beyond = leg & ~body
    assert (grown & body).sum() == body.sum()
    # (the smoothing and the opening take a pixel or so off its tip and edges)
    assert (grown & beyond).sum() >= 0.7 * beyond.sum()
    # a blurred edge's rim is no part (it would grow the contour every frame), and a piece
    # that does not touch the prediction is something else
    assert not (grown & rim & ~leg).any()
    assert not (grown & blob).any()


def test_nothing_is_taken_where_the_evidence_is_mild_or_far():
    body, leg, _rim, _blob, evidence = _scene()
    mild = np.where(leg & ~body, -0.5, evidence)
    assert (grow_parts(body, mild) == body).all()
    # a leg less than PART_FAR px out of the prediction is the morphing's to find
    yy, _ = np.mgrid[:80, :80]
    short = leg & (yy < 42 + PART_FAR - 1)
    evidence_short = np.where(leg & ~short, 3.0, evidence)
    assert (grow_parts(body, evidence_short) == body).all()
    # and never farther than PART_REACH px from it
    long_leg = np.zeros_like(body)
    long_leg[38:75, 38:43] = True
    far = np.where(long_leg, -3.0, evidence)
    grown = grow_parts(body, far)
    assert (grown & long_leg & ~body).any()
    assert not (grown & (yy > 42 + PART_REACH)).any()
