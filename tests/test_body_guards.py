"""The body's guards against a swing foot in the ground and against a step's curve read across a
heel strike (body_motion/swing_foot_guard.py: ankle_lift; body_motion/walk_samples.py: StepCurves)."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion.swing_foot_guard import GUARD_ACCELERATION, GUARD_GRID, GUARD_RATE, ankle_lift
from klaw_ocp.body_motion.walk_samples import StepCurves
from klaw_ocp.kinematics.leg_geometry import knee_flexion_for_reach, leg_ik, reach_for_knee_flexion

BODY = Body(height=1.8, mass=80.0)


def test_knee_flexion_and_reach_are_inverses_also_at_the_straight_knee():
    flexion = np.array([0.0, 1e-6, 0.01, 0.3, 1.2, 2.5])
    assert knee_flexion_for_reach(BODY, reach_for_knee_flexion(BODY, flexion)) == pytest.approx(flexion, abs=2e-8)
    hip, ankle = np.array([[0.0, 1.0]]), np.array([[0.1, 0.2]])
    assert knee_flexion_for_reach(BODY, np.hypot(0.1, 0.8)) == pytest.approx(leg_ik(BODY, hip, ankle)[1][0], abs=1e-12)
    assert knee_flexion_for_reach(BODY, BODY.l3 + BODY.l4 + 1e-3) == 0.0      # beyond reach: straight


def _straight_leg_sinking(depth: float):
    """A straight, vertical swing leg on a 2 ms grid over 0.3 s whose ankle dips ``depth`` below
    l9 in the middle (a raised cosine over 0.1-0.2 s), with a level foot (lowest point = ankle - l9)."""
    grid = np.arange(0.0, 0.3 + 1e-12, GUARD_GRID)
    dip = depth * np.where((grid > 0.1) & (grid < 0.2), 0.5 * (1 - np.cos(2 * np.pi * (grid - 0.1) / 0.1)), 0.0)
    hip_y = BODY.l3 + BODY.l4 + BODY.l9
    ankle = np.column_stack([np.zeros(len(grid)), BODY.l9 - dip])
    hip = np.column_stack([np.zeros(len(grid)), hip_y - dip])
    return grid, hip, ankle, ankle[:, 1] - BODY.l9


@pytest.mark.parametrize("depth", [0.001, 0.004, 0.03])
def test_the_lift_raises_the_foot_onto_the_ground_with_a_smooth_knee(depth):
    grid, hip, ankle, lowest = _straight_leg_sinking(depth)
    lift = ankle_lift(BODY, grid, hip, ankle, lowest)
    assert np.all(lowest + lift >= -1e-12)                       # never below the ground
    assert lift[0] == 0.0 and lift[-1] == 0.0                     # the leg of toe-off and heel strike
    if depth <= 0.004:   # only near where it is needed (a deeper bend takes longer to come and go:
        # 1 cm of a straight leg is a 17° bend, which within GUARD_ACCELERATION spans the whole grid)
        assert np.all(lift[(grid < 0.02) | (grid > 0.28)] == 0.0)
    # the knee the body shows bends smoothly: its rate within GUARD_RATE, its acceleration within
    # GUARD_ACCELERATION (the bend's second differences; the hip's own dip bends nothing, the leg
    # staying straight under it) where the bend can come and go within it (a deeper one asks for
    # more acceleration)
    knee = knee_flexion_for_reach(BODY, hip[:, 1] - ankle[:, 1] - lift)
    assert np.abs(np.diff(knee)).max() <= GUARD_RATE * GUARD_GRID * (1 + 1e-5)   # round-off near the straight knee
    if depth <= 0.004:
        assert np.abs(np.diff(knee, 2)).max() <= GUARD_ACCELERATION * GUARD_GRID ** 2 * (1 + 1e-3)
    # the least such lift: where the requirement is at its deepest, the foot touches the ground
    deepest = np.argmin(lowest)
    assert lowest[deepest] + lift[deepest] == pytest.approx(0.0, abs=1e-9)


def test_no_lift_where_the_foot_clears_the_ground():
    grid, hip, ankle, lowest = _straight_leg_sinking(0.01)
    assert np.all(ankle_lift(BODY, grid, hip, ankle + [0.0, 0.02], lowest + 0.02) == 0.0)


def test_a_step_curve_is_read_on_its_own_step_at_a_heel_strike_instant():
    """A sample of step k a round-off short of its heel strike (τ one ulp below t_step, as a
    frame time k/fps can give) takes step k's end, not step k+1's start, though its step
    coordinate u = k + τ/t_step rounds to k + 1 (a single frame's jump by a step length)."""
    t_step = np.array([0.36] * 20)
    pieces = [(k, np.array([0.0, 0.18, 0.36]), np.array([[0.0], [1.0], [2.0]]) + 10 * k, np.ones((3, 1)))
              for k in range(20)]
    curves = StepCurves.of(t_step, pieces)
    tau = np.nextafter(0.36, 0.0)
    assert 16 + tau / 0.36 == 17.0                               # the step coordinate rounds over
    assert curves(np.array([16]), np.array([tau]))[0, 0] == pytest.approx(162.0, abs=1e-9)
    assert curves(np.array([17]), np.array([0.0]))[0, 0] == pytest.approx(170.0, abs=1e-12)
    assert curves(np.array([16, 3]), np.array([0.09, 0.27]))[:, 0] == pytest.approx([160.5, 31.5], abs=1e-3)
