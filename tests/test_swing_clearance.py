"""The thigh's peak planned for a swing leg high enough for a foot (control/swing_clearance.py,
issue #36 item 6): the least retraction whose lowest ankle clears l9 by the margin, found in few
solves; a step that clears keeps its own; one that cannot gets the most lifting retraction tried."""
import math

import pytest

from klaw_ocp.body import Body
from klaw_ocp.control import swing_clearance as sc
from klaw_ocp.errors import ConvergenceError

BODY = Body(height=1.8, mass=80.0)


@pytest.fixture
def ankle_of_retraction(monkeypatch):
    """A swing whose lowest ankle (m above l9) is a given function of the retraction (deg): the
    'swings' a solve returns carry their retraction, lowest_ankle reads the function."""
    state = {"solves": 0}

    def install(lowest):
        monkeypatch.setattr(sc, "lowest_ankle", lambda body, swings, origin_x, pelvis: lowest(swings))

        def solve(deg):
            state["solves"] += 1
            if lowest(deg) is None:
                raise ConvergenceError(0, "swing2", 1.0, "no")
            return (deg, None)
        return solve
    return install, state


def test_a_swing_that_clears_keeps_its_retraction(ankle_of_retraction):
    install, state = ankle_of_retraction
    solve = install(lambda deg: 0.01)
    result, deg = sc.clearance_retraction(BODY, solve, 0.0, 0.0)
    assert deg == 0.0 and result == (0.0, None) and state["solves"] == 1


@pytest.mark.parametrize("hint, solves", [(3.0, 1), (2.0, None), (6.0, None)])
def test_the_step_befores_retraction_is_tried_first(ankle_of_retraction, hint, solves):
    """Where the hint clears within the tolerance it is taken at once; below or above, the search
    brackets the least retraction from it."""
    install, state = ankle_of_retraction
    target = sc.CLEARANCE_MARGIN_REL * BODY.l1
    lowest = lambda deg: target + (deg - 3.0) * 1.5e-3 + 1e-5     # noqa: E731  (clears from 2.99°)
    solve = install(lowest)
    result, deg = sc.clearance_retraction(BODY, solve, 0.0, 0.0, hint)
    assert result[0] == deg and target <= lowest(deg) <= target + sc.CLEARANCE_TOLERANCE_REL * BODY.l1
    if solves is not None:
        assert state["solves"] == solves and deg == hint


@pytest.mark.parametrize("slope_mm_per_deg, deficit_mm", [(1.7, 5.0), (2.3, 25.0), (0.9, 2.0), (4.0, 0.5)])
def test_the_least_retraction_that_clears_is_found_in_few_solves(ankle_of_retraction, slope_mm_per_deg, deficit_mm):
    install, state = ankle_of_retraction
    # a gently curved lift, as the thigh's cosine gives
    lowest = lambda deg: (-deficit_mm + slope_mm_per_deg * deg - 0.02 * deg ** 2) / 1000   # noqa: E731
    solve = install(lowest)
    result, deg = sc.clearance_retraction(BODY, solve, 0.0, 0.0)
    target, tolerance = sc.CLEARANCE_MARGIN_REL * BODY.l1, sc.CLEARANCE_TOLERANCE_REL * BODY.l1
    assert result[0] == deg and target <= lowest(deg) <= target + tolerance
    assert state["solves"] <= 1 + sc.MAX_SEARCH_SOLVES


def test_a_swing_that_cannot_clear_gets_the_most_lifting_retraction_tried(ankle_of_retraction):
    install, _ = ankle_of_retraction
    solve = install(lambda deg: None if deg > 12 else (-40 + deg) / 1000)
    result, deg = sc.clearance_retraction(BODY, solve, 0.0, 0.0)
    assert 0 < deg <= 12 and result[0] == deg


def test_the_lowest_ankle_reads_the_parabola_between_nodes():
    import numpy as np
    from dataclasses import dataclass

    @dataclass
    class Swing:
        name: str
        t: np.ndarray
        states: np.ndarray

    @dataclass
    class Level:          # a pelvis that leaves the stance hip where it is
        def swing_side_hips(self, t, hips):
            return hips

    # a vertical stance leg of length w and a vertical thigh under it, whose knee bends so that
    # the ankle's height is a parabola in time, lowest a third of the way between two nodes
    t = np.linspace(0.0, 0.2, 9)
    w = BODY.l1 + 0.01
    theta4 = np.arccos(0.98 - 2.0 * (t - 0.1083) ** 2)
    states = np.zeros((len(t), 10))
    states[:, 0], states[:, 7] = w, theta4
    lowest = sc.lowest_ankle(BODY, [Swing("swing2", t, states)], 0.0, Level())
    exact = w - BODY.l3 - 0.98 * BODY.l4
    at_nodes = np.min(w - BODY.l3 - BODY.l4 * np.cos(theta4)[:-1])
    assert lowest == pytest.approx(exact, abs=1e-12) and lowest < at_nodes - 1e-6
