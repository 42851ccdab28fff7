"""The heel-up roots in closed form (kinematics/heel_up_roots.py) against brute force: the ankle
limit's pitch is the least root of θ5 = heel_off_theta5 that a fine scan of the pitch finds, with
θ5 rebuilt here from the pitched foot and a two-link leg of its own (knee bent and knee forward,
or the leg straight towards a hip beyond its reach). Also the swing foot's cone envelope in O(n)
against its n x n definition."""
import math

import numpy as np
import pytest
from hypothesis import example, given, settings, strategies as st

from klaw_ocp.body import Body
from klaw_ocp.body_motion.swing_foot_guard import GUARD_RATE, rate_limited_turn
from klaw_ocp.gait.attributes import LocomotionAttributes
from klaw_ocp.kinematics.heel_up_roots import MAX_PITCH
from klaw_ocp.kinematics.virtual_leg import StanceFoot

BODY = Body(1.8, 80)
ATTRS = LocomotionAttributes.defaults()
Q = math.radians(ATTRS.meta_off_theta6)
LIMIT = math.radians(ATTRS.heel_off_theta5)
ANKLE_X = 0.3
OFF = math.sqrt(BODY.l12 ** 2 - BODY.l9 ** 2)
M_X = ANKLE_X + OFF                                  # the metatarsal head on the ground
TOE_X = M_X + BODY.l13


def ankle_at(p):
    """The ankle (n, 2) of the foot pitched by p (n,) >= 0: clockwise about the metatarsal head up
    to Q, then about the toe tip."""
    p = np.atleast_1d(np.asarray(p, float))

    def clockwise(point, pivot, a):
        v = point - pivot
        return pivot + np.column_stack([v[:, 0] * np.cos(a) + v[:, 1] * np.sin(a),
                                        -v[:, 0] * np.sin(a) + v[:, 1] * np.cos(a)])
    ankle = clockwise(np.array([[ANKLE_X, BODY.l9]]), np.array([M_X, 0.0]), np.minimum(p, Q))
    return clockwise(ankle, np.array([TOE_X, 0.0]), np.maximum(p - Q, 0.0))


def theta5(p, hip):
    """θ5 (n,) of the leg from ``hip`` to the foot pitched by p (n,): the angle from the shank's
    upward axis counter-clockwise to the backward sole, the knee forward of the hip-ankle line."""
    p = np.atleast_1d(np.asarray(p, float))
    ankle = ankle_at(p)
    d_vec = hip - ankle
    d = np.hypot(d_vec[:, 0], d_vec[:, 1])
    towards_hip = d_vec / d[:, None]
    # straight where the hip is out of reach (pointing at it); else the knee l4 from the ankle and
    # l3 from the hip, turned from the hip's direction by the triangle's angle at the ankle, to the
    # side that puts it forward of the hip-ankle line
    cos_gamma = np.clip((BODY.l4 ** 2 + d ** 2 - BODY.l3 ** 2) / (2 * BODY.l4 * d), -1.0, 1.0)
    ups = []
    for a in (np.arccos(cos_gamma), -np.arccos(cos_gamma)):
        u = np.column_stack([towards_hip[:, 0] * np.cos(a) - towards_hip[:, 1] * np.sin(a),
                             towards_hip[:, 0] * np.sin(a) + towards_hip[:, 1] * np.cos(a)])
        knee = ankle + BODY.l4 * u
        ups.append((-d_vec[:, 0] * (knee - hip)[:, 1] + d_vec[:, 1] * (knee - hip)[:, 0], u))
    up = np.where((ups[0][0] >= ups[1][0])[:, None], ups[0][1], ups[1][1])
    up = np.where((d >= BODY.l1)[:, None], towards_hip, up)
    back = np.column_stack([-np.cos(p), np.sin(p)])      # the sole turned clockwise by p
    return np.arctan2(up[:, 0] * back[:, 1] - up[:, 1] * back[:, 0], np.sum(up * back, axis=1)) % (2 * np.pi)


def _first_crossing(f, grid):
    """The least zero of ``f`` (vectorised) where it first falls to <= 0 on ``grid`` (bisected to
    1e-13); None if it never does."""
    below = np.flatnonzero(f(grid) <= 0)
    if not below.size:
        return None
    lo, hi = grid[below[0] - 1], grid[below[0]]
    while hi - lo > 1e-13:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if f(mid)[0] > 0 else (lo, mid)
    return hi


def scanned_root(hip, points=20000):
    """The least pitch at which θ5 - LIMIT falls to zero: a fine scan, then bisection to 1e-13.
    θ5 has a kink where the leg straightens (its hip just out of reach), where it can dip below
    the limit for less than the scan's spacing: the scan includes those pitches."""
    excess = lambda p: theta5(p, hip) - LIMIT
    if excess(0.0)[0] <= 0:
        return 0.0
    grid = np.linspace(0.0, MAX_PITCH, points)
    reach = lambda p: np.hypot(*(hip - ankle_at(p)).T) - BODY.l1
    kinks = [r for g in (reach, lambda p: -reach(p)) if (r := _first_crossing(g, grid)) is not None]
    root = _first_crossing(excess, np.union1d(grid, [Q, *kinks]))
    return MAX_PITCH if root is None else root


def foot():
    return StanceFoot.standing(BODY, ATTRS, ANKLE_X, 0.5)


def kind(hip, p):
    """Which case the root is: the flat foot's θ5 below the limit, the knee bent or the leg
    straight about the metatarsal head or the toe tip, or no root."""
    if p == 0:
        return "flat"
    if p == MAX_PITCH:
        return "never"            # the ankle does not stop giving before the foot stands on its toe
    where = "head" if p <= Q else "toe"
    return ("straight-" if np.hypot(*(hip - ankle_at(p)[0])) >= BODY.l1 - 1e-9 else "bent-") + where


# hips from the metatarsal head: (distance / l1, angle from the vertical), one per case
CASES = {"flat": (1.1, -0.5), "bent-head": (0.92, -0.35), "straight-head": (1.12, 0.55),
         "bent-toe": (0.9, 0.5), "straight-toe": (1.12, 0.8), "never": (0.82, 0.9)}


def hip_at(r, a):
    return np.array([M_X + r * BODY.l1 * math.sin(a), r * BODY.l1 * math.cos(a)])


@pytest.mark.parametrize("case", list(CASES))
def test_the_examples_cover_every_case(case):
    hip = hip_at(*CASES[case])
    p = foot().ankle_limit_pitch(hip[None])[0]
    assert kind(hip, p) == case
    assert p == pytest.approx(scanned_root(hip), abs=1e-9)


@settings(max_examples=150, deadline=None)
@given(r=st.floats(0.8, 1.2), a=st.floats(-0.6, 0.9))
@example(*CASES["flat"])
@example(*CASES["bent-head"])
@example(*CASES["straight-head"])
@example(*CASES["bent-toe"])
@example(*CASES["straight-toe"])
@example(*CASES["never"])
def test_the_ankle_limit_pitch_is_the_scans_least_root(r, a):
    hip = hip_at(r, a)
    assert foot().ankle_limit_pitch(hip[None])[0] == pytest.approx(scanned_root(hip), abs=1e-9)


def test_many_hips_at_once_are_each_hip_alone():
    hips = np.array([hip_at(*rc) for rc in CASES.values()])
    together = foot().ankle_limit_pitch(hips)
    assert list(together) == [foot().ankle_limit_pitch(h[None])[0] for h in hips]


@settings(max_examples=60, deadline=None)
@given(st.lists(st.floats(-0.3, 0.3), min_size=2, max_size=300), st.integers(0, 2 ** 32 - 1))
def test_the_rate_limited_turn_is_the_cone_envelope_by_its_definition(shape, seed):
    """The swing foot's turn away from its schedule (swing_foot_guard.grounded_angles) in O(n) equals
    its n x n definition: max_j(part_j - rate |t_i - t_j|), capped by the cones from both ends."""
    grid = 0.1 + 0.002 * np.arange(len(shape))
    required = np.array(shape) * (np.random.default_rng(seed).random(len(shape)) < 0.3)
    expected = np.zeros(len(grid))
    ends = GUARD_RATE * np.minimum(grid - grid[0], grid[-1] - grid)
    for sign in (1.0, -1.0):
        part = np.maximum(sign * required, 0.0)
        cone = part[None, :] - GUARD_RATE * np.abs(grid[:, None] - grid[None, :])
        expected += sign * np.minimum(cone.max(axis=1), ends)
    np.testing.assert_allclose(rate_limited_turn(grid, required), expected, rtol=0, atol=1e-14)
