"""Heel-strike map (section 4) and lock maps (section 4.2, eq. 5): what they conserve and what not."""
from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from _dynamics_support import BODIES
from klaw_ocp.dynamics import (CONSERVED, LOCK_RULES, NOT_CONSERVED, heel_strike_conserved,
                               heel_strike_map, impact_functions, knee_lock_map, stance_energy,
                               stance_hip, stance_lock_map, swing_energy)
from klaw_ocp.errors import ConfigError

BODY = BODIES[0]
TOL = 1e-12


def _close(a, b, scale=1.0):
    np.testing.assert_allclose(a, b, rtol=TOL, atol=TOL * scale)


def _momentum_scale(body):
    return body.mass * body.height * 5.0  # kg m^2/s: the size of the momenta in these tests


angles = st.floats(-0.6, 0.6)
rates = st.floats(-3.0, 3.0)
pre_impact = st.tuples(st.floats(0.8, 1.1), angles, angles, rates, rates, rates)
offsets = st.tuples(st.floats(0.2, 1.2), st.floats(-0.1, 0.1))


# ---- heel strike -----------------------------------------------------------------------------

@settings(max_examples=60, deadline=None)
@given(pre=pre_impact, offset=offsets, old_x=st.floats(-5, 5), body=st.sampled_from(BODIES))
def test_heel_strike_conserves_the_documented_quantities(pre, offset, old_x, body):
    x_pre = np.array(pre) * np.array([body.l1, 1, 1, 1, 1, 1])
    old_ankle = np.array([old_x, body.l9])
    new_ankle = old_ankle + offset
    x_post = heel_strike_map(body, x_pre, offset)
    before = heel_strike_conserved(body, x_pre, old_ankle, about=new_ankle)
    after = heel_strike_conserved(body, x_post, new_ankle)
    for key in CONSERVED:
        _close(after[key], before[key], _momentum_scale(body))
    # theta2 and theta2d pass through untouched; the hip is where stance_hip puts it
    assert x_post[2] == x_pre[2] and x_post[5] == x_pre[5]
    pos, vel = stance_hip(body, x_post, new_ankle)
    _close(pos, before["hip"], 10.0)
    _close(vel, before["hip_velocity"], 10.0)
    # mapping back onto the old ankle restores the pre-impact state
    _close(heel_strike_map(body, x_post, -np.asarray(offset)), x_pre, 10.0)


def test_heel_strike_does_not_conserve_the_leg_angular_momentum():
    """The explicit choice: the stance leg's (and so the model's) angular momentum about the new
    ankle jumps; only the upper body's quantities and the hip motion are conserved."""
    x_pre = np.array([0.95 * BODY.l1, 0.3, 0.1, 0.2, -1.1, 0.4])
    offset = np.array([0.6, 0.0])
    before = heel_strike_conserved(BODY, x_pre, [0, 0], about=offset)
    after = heel_strike_conserved(BODY, heel_strike_map(BODY, x_pre, offset), offset)
    assert set(CONSERVED).isdisjoint(NOT_CONSERVED)
    for key in NOT_CONSERVED:
        assert abs(after[key] - before[key]) > 1e-3 * abs(before[key]), key


@settings(max_examples=40, deadline=None)
@given(w=st.floats(0.8, 1.1), th1=st.floats(0.05, 0.6), th1d=rates, th2=angles, th2d=rates)
def test_heel_strike_mirror(w, th1, th1d, th2, th2d):
    """Symmetric step with a horizontal hip velocity: (w, th1, wd, th1d) -> (w, -th1, -wd, th1d)."""
    w *= BODY.l1
    wd = w * th1d * np.tan(th1)  # makes the hip velocity horizontal: wd cos th1 = w th1d sin th1
    x_post = heel_strike_map(BODY, [w, th1, th2, wd, th1d, th2d], [2 * w * np.sin(th1), 0.0])
    _close(x_post, [w, -th1, th2, -wd, th1d, th2d], 10.0)


def test_heel_strike_sx_core_matches_numeric():
    fn = impact_functions()["heel_strike"]
    x, off = np.array([0.9, 0.2, -0.1, 0.3, -1.0, 0.5]), np.array([0.5, 0.01])
    _close(np.asarray(fn(x, off)).ravel(), heel_strike_map(BODY, x, off), 10.0)


def test_heel_strike_rejects_bad_states():
    with pytest.raises(ConfigError, match="x_pre"):
        heel_strike_map(BODY, [0.9, 0.2, 0.1, 0.0, 0.0], [0.5, 0.0])
    with pytest.raises(ConfigError, match="positive leg length"):
        heel_strike_map(BODY, [-0.9, 0.2, 0.1, 0.0, 0.0, 0.0], [0.5, 0.0])


# ---- lock maps ---------------------------------------------------------------------------------

def _momenta(kinetic, qd):
    """Generalized momenta dT/dqd by central differences; T is quadratic in qd, so this is exact
    up to rounding (independent of the M the maps use)."""
    out = []
    for j in range(len(qd)):
        step = np.zeros(len(qd))
        step[j] = 1.0
        out.append((kinetic(qd + step) - kinetic(qd - step)) / 2.0)
    return np.array(out)


stance_states = st.tuples(st.floats(0.8, 1.1), angles, angles, rates, rates, rates)


@settings(max_examples=50, deadline=None)
@given(state=stance_states, body=st.sampled_from(BODIES))
def test_stance_lock_momentum_rule(state, body):
    x = np.array(state) * np.array([body.l1, 1, 1, 1, 1, 1])
    x_post = stance_lock_map(body, x)
    assert x_post[3] == 0.0 and np.array_equal(x_post[:3], x[:3])

    def kinetic(qd):
        return stance_energy(body, x[:3], qd)[0]

    _close(_momenta(kinetic, x_post[3:])[1:], _momenta(kinetic, x[3:])[1:], _momentum_scale(body))
    assert kinetic(x_post[3:]) <= kinetic(x[3:]) * (1 + 1e-14)
    _close(stance_lock_map(body, x_post), x_post, 10.0)  # idempotent


swing_states = st.tuples(st.floats(-1.2, 1.2), st.floats(0.0, 2.0), st.floats(-6, 6), st.floats(-6, 6))


@settings(max_examples=50, deadline=None)
@given(state=swing_states, hip_vel=st.tuples(st.floats(-2, 2), st.floats(-1, 1)), body=st.sampled_from(BODIES))
def test_knee_lock_momentum_rule(state, hip_vel, body):
    """theta4d -> 0 and dT/dtheta3d -- including the hip-velocity terms -- is unchanged."""
    x = np.array(state)
    x_post = knee_lock_map(body, x, hip_vel)
    assert x_post[3] == 0.0 and np.array_equal(x_post[:2], x[:2])

    def kinetic(qd, v=hip_vel):
        return swing_energy(body, x[:2], qd, [0.0, 1.0], v)[0]

    _close(_momenta(kinetic, x_post[2:])[0], _momenta(kinetic, x[2:])[0], _momentum_scale(body))
    # with the hip at rest the map is an M-orthogonal projection: T cannot grow
    fixed = lambda qd: kinetic(qd, (0.0, 0.0))  # noqa: E731
    assert fixed(x_post[2:]) <= fixed(x[2:]) * (1 + 1e-14)


def test_zero_rule_is_the_paper_and_differs_from_momentum():
    x = np.array([0.9, 0.3, -0.2, 0.5, -1.0, 0.4])
    np.testing.assert_array_equal(stance_lock_map(BODY, x, rule="zero"), [0.9, 0.3, -0.2, 0.0, -1.0, 0.4])
    assert np.abs(stance_lock_map(BODY, x) - stance_lock_map(BODY, x, rule="zero")).max() > 1e-3
    xs = np.array([-0.2, 0.8, 2.0, -4.0])
    np.testing.assert_array_equal(knee_lock_map(BODY, xs, [1.0, 0.0], rule="zero"), [-0.2, 0.8, 2.0, 0.0])
    assert abs(knee_lock_map(BODY, xs, [1.0, 0.0])[2] - 2.0) > 1e-2


@pytest.mark.parametrize("call", [lambda: stance_lock_map(BODY, np.ones(6), rule="elastic"),
                                  lambda: knee_lock_map(BODY, np.ones(4), [0, 0], rule="Momentum")])
def test_unknown_lock_rule_lists_the_allowed_ones(call):
    with pytest.raises(ConfigError) as err:
        call()
    for rule in LOCK_RULES:
        assert repr(rule) in str(err.value)
