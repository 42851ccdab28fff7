"""Every step's swing foot in one pass (body_motion/swing_foot_guard.py: lifted_feet) is the
per-step form (lifted_foot) to the last bit, on real walks: in the body's swing legs and in the
summary's swing-foot clearance."""
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from klaw_ocp.body_motion.swing_foot_guard import guard_grid, lifted_feet, lifted_foot, sole_heights
from klaw_ocp.results import hip_offsets, swing_foot_clearance, swing_foot_clearances
from klaw_ocp.walk import simulate_walk

ROOT = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="module")
def walk():
    """A walk from rest to rest: its first and last steps lift the ankle (the dynamic leg too low)."""
    return simulate_walk(ROOT / "configs" / "start_stop_5kmh.yaml", method="multiple-shooting")


def _dynamic_leg_on_grid(body, step, grid):
    """A smooth stand-in for the leg on the guard grid: hip, ankle (m, 2), shank angle (m,),
    with the ankle low enough mid-swing that the foot needs both the turn and the lift."""
    s = (grid - grid[0]) / (grid[-1] - grid[0])
    hip = np.column_stack([step.origin_x + 0.5 * s, np.full(len(grid), 0.9)])
    ankle = np.column_stack([hip[:, 0] + 0.3 * np.cos(3 * s), 0.09 - 0.1 * np.sin(np.pi * s)])
    return hip, ankle, 0.6 * np.sin(4 * s)


def test_every_step_at_once_is_each_step_alone(walk):
    body, steps = walk.spec.body, walk.steps
    feet = [step.swing_foot for step in steps]
    grids = [guard_grid(foot) for foot in feet]
    times = [np.linspace(foot.t_toe_off, foot.t_heel_strike, 7 + k)[::-1] for k, foot in enumerate(feet)]
    legs = [_dynamic_leg_on_grid(body, step, grid) for step, grid in zip(steps, grids)]
    together = lifted_feet(body, feet, times, grids, *(np.concatenate(part) for part in zip(*legs)))
    alone = [lifted_foot(body, foot, t, grid, *leg) for foot, t, grid, leg in zip(feet, times, grids, legs)]
    for got, expected in zip(together, zip(*alone)):
        # to round-off: numpy's transcendental loops may differ by an ulp between array lengths
        np.testing.assert_allclose(got, np.concatenate(expected), rtol=0, atol=1e-12)
    assert np.concatenate([a[2] for a in alone]).max() > 0.0     # the lift is exercised


def test_the_summary_clearance_of_all_steps_is_each_steps_own(walk):
    body, offsets = walk.spec.body, hip_offsets(walk)
    hips = [[np.array([step.origin_x, body.l9]) + o for o in step_offsets]
            for step, step_offsets in zip(walk.steps, offsets)]
    together = swing_foot_clearances(body, walk.steps, hips)
    # to round-off: numpy's transcendental loops may differ by an ulp between array lengths
    assert together == [pytest.approx(swing_foot_clearance(body, step, h), abs=1e-12) for step, h in zip(walk.steps, hips)]
    assert together == [pytest.approx(_per_step_clearance(body, step, h), abs=1e-12) for step, h in zip(walk.steps, hips)]
    assert max(entry["ankle_lift_max_m"] for entry in together) > 0.0


def _per_step_clearance(body, step, hips):
    """The summary's clearance as it was computed before the one-pass form, step by step."""
    names = ("swing1", "swing2", "swing3")
    subs = [step.subphase(name) for name in names]
    t = np.concatenate([sub.t for sub in subs])
    x = np.vstack([sub.states[:, :7] for sub in subs])
    theta4 = np.concatenate([sub.states[:, 7] if sub.name != "swing3" else np.zeros(len(sub.t)) for sub in subs])
    hips = np.vstack([h for sub, h in zip(step.subphases, hips) if sub.name in names])
    (dx, dy), _, _ = step.pelvis.swing_hip_offset(t)   # the leg hangs from the pelvis's other hip
    hips = hips + np.column_stack([dx, dy])
    shank = x[:, 6] + theta4
    ankle = hips - body.l3 * np.column_stack([np.sin(x[:, 6]), np.cos(x[:, 6])]) \
        - body.l4 * np.column_stack([np.sin(shank), np.cos(shank)])
    grid = guard_grid(step.swing_foot)
    on_grid = lambda v: np.interp(grid, t, v)
    theta5, theta6, lift = lifted_foot(
        body, step.swing_foot, t, grid, np.column_stack([on_grid(hips[:, 0]), on_grid(hips[:, 1])]),
        np.column_stack([on_grid(ankle[:, 0]), on_grid(ankle[:, 1])]), on_grid(shank))
    heel, toe = sole_heights(body, ankle[:, 1] + lift, shank, theta5, theta6)
    inside = (t > t[0]) & (t < t[-1])
    swing2 = (t >= subs[1].t[0]) & (t <= subs[1].t[-1])
    return {"toe_min_m": float(toe[inside].min()), "heel_min_m": float(heel[inside].min()),
            "midswing_toe_min_m": float(toe[swing2].min()), "ankle_lift_max_m": float(lift.max())}


def test_the_swing_ankle_leaves_toe_off_at_the_stance_rate_and_is_neutral_from_mid_swing():
    """The schedule (kinematics/swing_foot.py, issues #34, #36): θ5 starts at its toe-off value
    with the stance ankle's rate (the push-off's plantarflexion runs on), reaches θ5_t1 at t1 at
    rest, its acceleration never above SWING1_ANKLE_BRAKE (two constant accelerations, the first
    that one: C1, the least peak a frame-to-frame rate jump sees); the foot swing2's path
    constrains holds it through the first half of swing2 and is back at the heel-strike angle by
    t2 at rest; numpy and CasADi give the same numbers."""
    import casadi as ca

    from klaw_ocp.kinematics.swing_foot import (SCHEDULE_FIELDS, SWING1_ANKLE_BRAKE, SWING2_HOLD_FRACTION, SwingFoot,
                                                schedule_angles)
    foot = SwingFoot(0.1, 0.3, 0.45, 0.55, 1.40, 0.5, 1.80, 1.5708, 0.0, -5.0, 0.9)
    h = 1e-5
    th5 = lambda t: float(foot.angles(np.array([t]))[0][0])
    rate = lambda t: (th5(t + h) - th5(t - h)) / (2 * h)
    accel = lambda t: (th5(t + h) - 2 * th5(t) + th5(t - h)) / h ** 2
    assert th5(0.1) == pytest.approx(1.40) and (th5(0.1 + 1e-7) - th5(0.1)) / 1e-7 == pytest.approx(-5.0, rel=1e-4)
    assert min(th5(t) for t in np.linspace(0.1, 0.3, 201)) < 1.40 - 0.05       # plantarflexes on
    arriving = (th5(0.3) - th5(0.3 - h)) / h
    assert th5(0.3) == pytest.approx(1.80) and arriving == pytest.approx(0.0, abs=SWING1_ANKLE_BRAKE * h)
    hold = 0.3 + SWING2_HOLD_FRACTION * 0.15
    assert th5(hold) == pytest.approx(1.80) and th5(0.45) == pytest.approx(1.5708)
    assert rate(0.45) == pytest.approx(0.0, abs=1e-3) and th5(0.55) == pytest.approx(1.5708)   # (h x its acceleration step)
    assert max(abs(accel(t)) for t in np.linspace(0.1 + 2 * h, 0.3 - 2 * h, 401)) <= SWING1_ANKLE_BRAKE * (1 + 1e-3)
    assert accel(0.1 + 1e-3) == pytest.approx(SWING1_ANKLE_BRAKE, rel=1e-3)       # braking the push-off
    t = ca.SX.sym("t")
    values = {name: getattr(foot, name) for name in SCHEDULE_FIELDS}
    f = ca.Function("f", [t], [schedule_angles(t, values, lambda x, lo, hi: ca.fmin(ca.fmax(x, lo), hi))[0]])
    for tt in np.linspace(0.1, 0.55, 19):
        assert float(f(tt)) == pytest.approx(th5(tt), abs=1e-14)


def test_the_body_s_swing_ankle_relaxes_with_the_knee():
    """The foot the body shows (kinematics/swing_foot.py): the same swing1, then through swing2 it
    keeps θ5_t1's dorsiflexion by S(u), u the knee's flexion over its t1 flexion (1 where it
    flexes on past it) for KNEE_SHARE_OF_RELAXATION and the time left to t2 for the rest,
    reaching the heel-strike angle as the knee reaches full extension at t2, at rest, and holding
    it through swing3."""
    from klaw_ocp.kinematics.swing_foot import KNEE_SHARE_OF_RELAXATION as k, SwingFoot
    knee_t1 = 0.9
    foot = SwingFoot(0.1, 0.3, 0.45, 0.55, 1.40, 0.5, 1.80, 1.5708, 0.0, -5.0, knee_t1)
    # a knee that flexes on a little after t1, then extends to 0 at t2 at rest (as swing2's does)
    s = lambda t: np.clip((t - 0.3) / 0.15, 0.0, 1.0)
    knee = lambda t: knee_t1 * (1 + 0.3 * np.sin(np.pi * s(t))) * (1 - s(t)) ** 2 * (1 + 2 * s(t))
    th5 = lambda t: float(foot.angles(np.array([t]), knee(np.array([t])))[0][0])
    relaxed = lambda u: 1.5708 + (1.80 - 1.5708) * u * u * (3 - 2 * u)
    h = 1e-5
    rate = lambda t: (th5(t + h) - th5(t - h)) / (2 * h)
    assert 0.5 <= k <= 1.0
    for t in np.linspace(0.1, 0.3, 9):           # swing1: the constrained foot's
        assert th5(t) == pytest.approx(float(foot.angles(np.array([t]))[0][0]), abs=1e-15)
    # the knee flexing on past its t1 angle: its share held, the time's relaxing
    assert th5(0.33) == pytest.approx(relaxed(k + (1 - k) * (1 - s(0.33))), abs=1e-12)
    for t in (0.4, 0.43):                         # relaxing with the knee and the time
        r = knee(np.array([t]))[0] / knee_t1
        assert th5(t) == pytest.approx(relaxed(k * r + (1 - k) * (1 - s(t))), abs=1e-12)
    assert rate(0.3 + 2 * h) == pytest.approx(0.0, abs=0.05)    # no rate jump at t1 (S'(1) = 0)
    assert th5(0.45 - 1e-9) == pytest.approx(1.5708, abs=1e-9) and abs(rate(0.45 - 2 * h)) < 1e-3
    assert th5(0.5) == pytest.approx(1.5708) and th5(0.55) == pytest.approx(1.5708)


@settings(max_examples=200, deadline=None)
@given(st.floats(1.0, 2.2), st.floats(-12.0, 12.0), st.floats(-1.0, 1.0), st.floats(0.08, 0.5))
def test_the_swing1_ankle_meets_both_ends_on_two_bounded_accelerations(theta0, rate0, travel, span):
    """kinematics/swing_foot._swing1_ankle: from (θ0, the push-off's rate) to (θ1, at rest) in
    ``span``, on two constant accelerations, neither above the larger of SWING1_ANKLE_BRAKE and the
    symmetric solution's (the least peak acceleration that meets both ends), whatever the signs."""
    from klaw_ocp.kinematics.swing_foot import SWING1_ANKLE_BRAKE, _swing1_ankle
    theta1 = theta0 + travel
    tau = np.linspace(0.0, span, 2001)
    theta = _swing1_ankle(tau, span, theta0, rate0, theta1, np.clip)
    assert theta[0] == pytest.approx(theta0, abs=1e-12) and theta[-1] == pytest.approx(theta1, abs=1e-9)
    h = tau[1]
    # the symmetric solution's acceleration, from both ends (with signs turned if the target is behind)
    sign = 1.0 if 2 * travel - rate0 * span >= 0 else -1.0
    r0, d = sign * rate0, sign * travel
    linear = 2 * r0 * span - 4 * d
    symmetric = (-linear + np.sqrt(linear ** 2 + 4 * span ** 2 * r0 ** 2)) / (2 * span ** 2)
    bound = max(SWING1_ANKLE_BRAKE, symmetric)
    assert (theta[1] - theta[0]) / h == pytest.approx(rate0, abs=bound * h + 1e-6)       # the push-off's rate
    assert abs(theta[-1] - theta[-2]) / h <= 2 * bound * h + 1e-6                  # at rest at t1
    assert np.abs(np.diff(theta, 2)).max() / h ** 2 <= bound * (1 + 1e-6) + 1e-6
