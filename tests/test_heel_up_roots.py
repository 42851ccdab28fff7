"""The heel-up reach pitch (kinematics/heel_up_roots.py) against brute force: the least pitch at
which the ankle of the heel-up foot, rebuilt here (about the metatarsal head, then through a C1
band about meta-off, then about the toe tip), is a given distance from the hip, found by a fine
scan. Also the swing foot's smooth turn on a band against its n x n definition."""
import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.body_motion.swing_foot_guard import GUARD_ACCELERATION, GUARD_GRID, GUARD_RATE, smooth_turn
from klaw_ocp.gait.attributes import LocomotionAttributes
from klaw_ocp.kinematics.heel_up_roots import MAX_PITCH
from klaw_ocp.kinematics.virtual_leg import StanceFoot

BODY = Body(1.8, 80)
ATTRS = LocomotionAttributes.defaults()
Q = math.radians(ATTRS.meta_off_theta6)
BAND = min(math.radians(12.0), Q / 2)
ANKLE_X = 0.3
OFF = math.sqrt(BODY.l12 ** 2 - BODY.l9 ** 2)
M_X = ANKLE_X + OFF                                  # the metatarsal head on the ground
TOE_X = M_X + BODY.l13


def ankle_at(p):
    """The ankle (n, 2) of the foot pitched by p (n,) >= 0: the toe segment turned up about the
    toe tip by p - θ6 (θ6 = p, then q, joined by a parabola over q ± BAND), the rest turned
    clockwise by p about the metatarsal head wherever that puts it."""
    p = np.atleast_1d(np.asarray(p, float))
    v = p - Q
    theta6 = np.where(v <= -BAND, p, np.where(v >= BAND, Q, p - (v + BAND) ** 2 / (4 * BAND)))
    rise = p - theta6
    head = np.column_stack([TOE_X - BODY.l13 * np.cos(rise), BODY.l13 * np.sin(rise)])
    dx, dy = -OFF, BODY.l9                           # the flat ankle less the flat head
    return head + np.column_stack([dx * np.cos(p) + dy * np.sin(p), -dx * np.sin(p) + dy * np.cos(p)])


def scanned_root(hip, radius, points=20000):
    """The least pitch at which the ankle comes within ``radius`` of the hip: a fine scan, then
    bisection to 1e-13; 0 if the flat foot's does, MAX_PITCH if none does."""
    gap = lambda p: np.hypot(*(hip - ankle_at(p)).T) - radius
    if gap(0.0)[0] <= 0:
        return 0.0
    grid = np.linspace(0.0, MAX_PITCH, points)
    below = np.flatnonzero(gap(grid) <= 0)
    if not below.size:
        return MAX_PITCH
    lo, hi = grid[below[0] - 1], grid[below[0]]
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if gap(mid)[0] > 0 else (lo, mid)
    return hi


def foot():
    return StanceFoot.standing(BODY, ATTRS, ANKLE_X, 0.5)


def kind(p):
    if p == 0:
        return "flat"
    if p == MAX_PITCH:
        return "never"
    return "head" if p <= Q - BAND else ("band" if p < Q + BAND else "toe")


def hip_at(r, a):
    return np.array([M_X + r * BODY.l1 * math.sin(a), r * BODY.l1 * math.cos(a)])


# hips from the metatarsal head (distance / l1, angle from the vertical) and the reach (/ l1)
CASES = {"flat": (0.95, 0.1, 1.0), "head": (1.09, 0.1, 0.996), "band": (1.15, 0.0, 1.0),
         "toe": (1.22, 0.0, 1.0), "never": (1.6, 0.0, 1.0)}


@pytest.mark.parametrize("case", list(CASES))
def test_the_examples_cover_every_case(case):
    r, a, f = CASES[case]
    hip = hip_at(r, a)
    p = foot().reach_pitch(hip[None], f)[0]
    assert kind(p) == case
    assert p == pytest.approx(scanned_root(hip, f * BODY.l1), abs=1e-9)


@settings(max_examples=150, deadline=None)
@given(r=st.floats(0.9, 1.3), a=st.floats(-0.4, 0.9), f=st.floats(0.9, 1.0))
@example(*CASES["flat"])
@example(*CASES["head"])
@example(*CASES["band"])
@example(*CASES["toe"])
def test_the_reach_pitch_is_the_scans_least_root(r, a, f):
    hip = hip_at(r, a)
    assert foot().reach_pitch(hip[None], f)[0] == pytest.approx(scanned_root(hip, f * BODY.l1), abs=1e-9)


def test_many_hips_at_once_are_each_hip_alone():
    hips = np.array([hip_at(r, a) for r, a, _ in CASES.values()])
    reach = np.array([f for *_, f in CASES.values()])
    together = foot().reach_pitch(hips, reach)
    assert list(together) == [foot().reach_pitch(h[None], f)[0] for h, f in zip(hips, reach)]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-0.3, 0.3), min_size=2, max_size=300), st.integers(0, 2 ** 32 - 1))
def test_the_smooth_turn_is_the_regularisation_by_its_definition(shape, seed):
    """The swing foot's turn away from its schedule (swing_foot_guard.grounded_angles) in O(n) and
    on a band equals its n x n definition: for each sign's part, the cone envelope max_j(part_j - R
    |t_i - t_j|), then its Lasry-Lions regularisation (sup- then inf-convolution with parabolas,
    λ = 2/A, μ = 1/A), capped by the fastest rise from either end (acceleration A, then rate R).
    Its rate stays within R; where the caps leave it alone it meets the requirement and its second
    differences stay within A h² (C1, |θ''| <= A). With escalations (the ankle lift's) it meets
    more of a requirement of one sign, never less."""
    grid = 0.1 + GUARD_GRID * np.arange(len(shape))
    required = np.array(shape) * (np.random.default_rng(seed).random(len(shape)) < 0.3)
    a, r = GUARD_ACCELERATION, GUARD_RATE
    near_end = np.minimum(grid - grid[0], grid[-1] - grid)
    d = np.abs(grid[:, None] - grid[None, :])
    cap = np.where(near_end * a < r, 0.5 * a * near_end ** 2, r * near_end - 0.5 * r * r / a)
    expected, capped = np.zeros(len(grid)), False
    for sign in (1.0, -1.0):
        part = np.maximum(sign * required, 0.0)
        cone = (part[None, :] - r * d).max(axis=1)
        u = (cone[None, :] - d * d * a / 4).max(axis=1)
        v = (u[None, :] + d * d * a / 2).min(axis=1)
        expected += sign * np.minimum(v, cap)
        capped |= bool(np.any(v > cap))
    turn = smooth_turn(grid, required)
    np.testing.assert_allclose(turn, expected, rtol=0, atol=1e-12)
    assert np.abs(np.diff(turn)).max(initial=0.0) <= r * GUARD_GRID * (1 + 1e-9) + 1e-12
    one_sign = not (np.any(required > 0) and np.any(required < 0))
    if not capped and one_sign:
        assert np.all(np.sign(required) * (turn - required) >= -1e-12)
    if not capped and len(grid) > 2:
        assert np.abs(np.diff(turn, 2)).max() <= a * GUARD_GRID ** 2 * (1 + 1e-9) + 1e-12
    if one_sign:
        escalated = smooth_turn(grid, required, escalations=4)
        shortfall = lambda x: np.maximum(np.abs(required) - np.abs(x), 0.0).max(initial=0.0)
        assert shortfall(escalated) <= shortfall(turn) + 1e-12
