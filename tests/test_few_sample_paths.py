"""The virtual leg's one-to-few-sample paths on Python floats (kinematics: ``heel_up_roots._FEW``,
``pitch_rules._FEW``, ``leg_geometry.leg_ik_float`` and ``FootPieces.ankle_float``,
``landing.starting_rates``) give the numbers of the array paths they stand in for, to the bit:
the walk's step asks for one to a few dozen samples at a time, the body for thousands, and a walk
must not depend on which of the two computed it."""
import math
from dataclasses import replace

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.gait.attributes import LocomotionAttributes
from klaw_ocp.kinematics import heel_up_roots, pitch_rules
from klaw_ocp.kinematics.landing import starting_rates, starting_rates_of
from klaw_ocp.kinematics.leg_geometry import FlatFoot, clamp, clamp_float, foot_pieces, leg_ik, leg_ik_float
from klaw_ocp.kinematics.virtual_leg import StanceFoot

ATTRS = LocomotionAttributes.defaults()
BODIES = (Body(1.8, 80), Body(1.5, 50))
#: meta-off limits: the walk's, a narrow band, none
LIMITS = (math.radians(ATTRS.meta_off_theta6), 0.2, 0.0)


def _hips(rng, body, ankle_x, n):
    """n hips around the metatarsal head, from well within the leg's reach to beyond it."""
    r, a = rng.uniform(0.85, 1.35, n), rng.uniform(-0.5, 1.0, n)
    head = ankle_x + body.metatarsal_reach
    return np.column_stack([head + r * body.l1 * np.sin(a), r * body.l1 * np.cos(a)])


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.5m"])
@pytest.mark.parametrize("limit", LIMITS)
def test_the_few_hips_reach_pitch_is_the_arrays(monkeypatch, body, limit):
    rng, foot = np.random.default_rng(1), FlatFoot(body, 0.3)
    for _ in range(300):
        n = int(rng.integers(1, 6))
        hips = _hips(rng, body, 0.3, n)
        radius = body.l1 * (rng.uniform(0.85, 1.0, n) if rng.random() < 0.7 else np.full(n, rng.uniform(0.85, 1.0)))
        few = heel_up_roots.reach_pitch(foot, limit, hips, radius)
        with monkeypatch.context() as patch:
            patch.setattr(heel_up_roots, "_FEW", 0)
            arrays = heel_up_roots.reach_pitch(foot, limit, hips, radius)
        assert np.array_equal(few, arrays), (hips, radius)


def _stance(rng, body) -> StanceFoot:
    """A stance's rules with a rocker, a knee schedule, maybe a held knee and a deficit."""
    t_step = rng.uniform(0.3, 0.7)
    hip = np.array([rng.uniform(-0.3, 0.0), 0.9 * body.l1])
    foot = StanceFoot.at_heel_strike(body, ATTRS, 0.2, hip, t_step, (rng.uniform(0.8, 1.5), 0.0))
    if rng.random() < 0.5:
        foot = replace(foot, knee_hold=rng.uniform(0.0, 0.3), t_hold=rng.uniform(0.1, t_step))
    if rng.random() < 0.5:
        single_t = np.sort(rng.uniform(0.0, t_step, 6))
        foot = replace(foot, single_t=tuple(single_t), single_deficit=tuple(rng.uniform(0.0, 0.05, 6)))
    return replace(foot, pitch_ds_floor=rng.uniform(0.0, 0.3) if rng.random() < 0.5 else 0.0)


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.5m"])
def test_one_stances_few_samples_pitch_is_the_arrays(monkeypatch, body):
    rng = np.random.default_rng(2)
    for _ in range(200):
        foot = _stance(rng, body)
        n = int(rng.integers(1, 25))
        t = np.sort(rng.uniform(0.0, foot.t_step + 0.2, n))
        hips = np.column_stack([rng.uniform(-0.2, 0.7, n), rng.uniform(0.85, 1.02, n) * body.l1])
        few = foot._rule_pitch(t, hips)
        with monkeypatch.context() as patch:
            patch.setattr(pitch_rules, "_FEW", 0)
            patch.setattr(heel_up_roots, "_FEW", 0)
            arrays = foot._rule_pitch(t, hips)
        assert all(np.array_equal(a, b) for a, b in zip(few, arrays)), (foot, t, hips)


@pytest.mark.parametrize("limit", LIMITS)
def test_one_samples_ankle_and_leg_are_the_arrays(limit):
    rng, body = np.random.default_rng(3), BODIES[0]
    foot, pieces = FlatFoot(body, 0.2), foot_pieces(body, limit)
    pitches = np.concatenate([rng.uniform(-0.6, 1.6, 400), [0.0, -0.0, limit, limit - 0.1, limit + 0.1]])
    for p, ankle in zip(pitches, foot.ankle_at(pitches, limit)):
        assert pieces.ankle_float(0.2, float(p)) == tuple(ankle.tolist())
        hip = (float(rng.uniform(-0.6, 0.8)), float(rng.uniform(0.3, 1.2) * body.l1))
        theta3, theta4, _ = leg_ik(body, np.array([hip]), ankle[None])
        assert leg_ik_float(body, *hip, *ankle.tolist()) == (float(theta3[0]), float(theta4[0]))


def test_one_foots_starting_rates_are_the_arrays():
    rng, body = np.random.default_rng(4), BODIES[0]
    for _ in range(300):
        foot = replace(StanceFoot.standing(body, ATTRS, 0.1, 0.5),
                       t_flat=float(rng.choice([0.0, rng.uniform(0.01, 0.2)])),
                       rocker_pitch=float(rng.choice([0.0, -rng.uniform(0, 0.5), rng.uniform(0, 0.3)])),
                       rocker_rate=rng.uniform(0, 30), meta_off_theta6=float(rng.choice(LIMITS)))
        hip, velocity = np.array([rng.uniform(-0.4, 0.6), rng.uniform(0.5, 1.1) * body.l1]), rng.uniform(-2, 2, 2)
        arrays = starting_rates_of(foot, np.array([foot.rocker_pitch]), np.array([foot.rocker_rate]), hip, velocity)[0]
        assert np.array_equal(starting_rates(foot, hip, velocity), arrays, equal_nan=True)


def test_clamp_of_a_number_is_numpys():
    for x in (-2.0, -1.0, -0.0, 0.0, 0.5, 1.0, 3.0, math.nan, math.inf, -math.inf):
        expected = clamp(np.array([x]), -1.0, 1.0)[0]
        got = clamp_float(x, -1.0, 1.0)
        same_sign = math.copysign(1, got) == math.copysign(1, expected)
        assert (math.isnan(got) and math.isnan(expected)) or (got == expected and same_sign)


def test_the_swing_side_hips_are_the_offsets_of_swing_hip_offset():
    """``PelvisSchedule.swing_side_hips`` evaluates the offset and its rate alone: the numbers of
    :func:`~klaw_ocp.kinematics.pelvis.swing_hip_offset`, one schedule or one per sample."""
    from klaw_ocp.kinematics.pelvis import PelvisSchedule
    rng = np.random.default_rng(5)
    for _ in range(100):
        n = int(rng.integers(1, 40))
        fields = [(0.1, 0.3), (-0.2, 0.2), (-0.2, 0.2), (0.0, 0.1), (0.3, 0.8)]
        pelvis = PelvisSchedule(*(rng.uniform(lo, hi, n) if rng.random() < 0.5 else float(rng.uniform(lo, hi))
                                  for lo, hi in fields))
        t, hips, velocities = rng.uniform(-0.1, 0.9, n), rng.uniform(-1, 1, (n, 2)), rng.uniform(-1, 1, (n, 2))
        (dx, dy), (vx, vy), _ = pelvis.swing_hip_offset(t)
        expected = hips + np.column_stack([dx, dy])
        assert np.array_equal(pelvis.swing_side_hips(t, hips), expected)
        other, other_velocities = pelvis.swing_side_hips(t, hips, velocities)
        assert np.array_equal(other, expected)
        assert np.array_equal(other_velocities, velocities + np.column_stack([vx, vy]))
