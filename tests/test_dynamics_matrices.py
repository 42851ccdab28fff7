"""The derived equations of motion against the printed Appendix A.1 / A.2 (ERRATA 1-4), the locked
variants, the hip kinematics, mirror symmetry and the numeric API's argument checks."""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from _dynamics_support import BODIES, printed_a1, printed_a2
from klaw_ocp.body import Body
from klaw_ocp.dynamics import (apply_lock, hip_kinematics, stance_accelerations, stance_bias,
                               stance_mass_matrix, stance_mass_bias, swing_accelerations, swing_bias,
                               swing_mass_matrix)
from klaw_ocp.errors import ConfigError

N_STATES = 60
TOL = 1e-12


def _stance_states(rng, body, n=N_STATES):
    q = np.column_stack([body.l1 * rng.uniform(0.7, 1.1, n), rng.uniform(-1.2, 1.2, (n, 2))])
    return q, rng.uniform(-5, 5, (n, 3)), rng.uniform(-300, 300, (n, 3))


def _swing_states(rng, n=N_STATES):
    q = np.column_stack([rng.uniform(-1.5, 1.5, n), rng.uniform(-0.2, 2.2, n)])
    return q, rng.uniform(-8, 8, (n, 2)), rng.uniform(-100, 100, (n, 2)), rng.uniform(-20, 20, (n, 2))


def _close(actual, expected, scale):
    """Equal to TOL relative to ``scale`` (the size of the terms that were summed)."""
    np.testing.assert_allclose(actual, expected, rtol=TOL, atol=TOL * scale)


def _weight(body):
    return body.mass * body.g * body.height  # J: the size of the gravity terms


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_stance_mass_matrix_and_bias_equal_printed_a1(body):
    rng = np.random.default_rng(1)
    for q, qd, force in zip(*_stance_states(rng, body)):
        A, B = printed_a1(body, q, qd, force)
        M = stance_mass_matrix(body, q)
        _close(M, A, np.abs(A).max())
        _close(stance_bias(body, q, qd) + force, B, max(np.abs(B).max(), _weight(body)))
        _close(stance_accelerations(body, q, qd, force), np.linalg.solve(A, B), 1e3 * np.abs(np.linalg.solve(A, B)).max())


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_swing_mass_matrix_and_bias_equal_printed_a2_with_errata_2(body):
    rng = np.random.default_rng(2)
    for q, qd, force, hip_acc in zip(*_swing_states(rng)):
        A, B = printed_a2(body, q, qd, hip_acc, force)
        _close(swing_mass_matrix(body, q), A, np.abs(A).max())
        _close(swing_bias(body, q, qd, hip_acc) + force, B, max(np.abs(B).max(), _weight(body)))
        acc = swing_accelerations(body, q, qd, force, hip_acc)
        _close(acc, np.linalg.solve(A, B), 1e3 * np.abs(acc).max())


def test_printed_a2_typo_differs_from_the_derivation():
    """The typo matters wherever theta4d != 0 and theta4 != theta4d: the transcription is faithful."""
    body = BODIES[0]
    q, qd = np.array([-0.3, 0.8]), np.array([1.0, -2.0])
    _, b_typo = printed_a2(body, q, qd, (0, 0), typo=True)
    assert abs(swing_bias(body, q, qd, [0, 0])[0] - b_typo[0]) > 1.0


def _locked_stance_system(body, q, qd, force):
    """The derived M, b + F after apply_lock(locked=1) on coordinate 0 (the rigid leg)."""
    qs, qds, fs = ca.SX.sym("q", 3), ca.SX.sym("qd", 3), ca.SX.sym("F", 3)
    p = ca.DM(body.dynamic_parameters())
    mass, bias = stance_mass_bias(qs, qds, p)
    mass, rhs = apply_lock(mass, bias + fs, 1, 0)
    fn = ca.Function("locked", [qs, qds, fs], [mass, rhs])
    mass, rhs = fn(q, qd, force)
    return np.asarray(mass), np.asarray(rhs).ravel()


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_rigid_stance_leg_errata_3(body):
    """Row/column 1 become (1, 0, 0), b1 = 0, wdd = 0; the rest is A.1 without w's row/column."""
    rng = np.random.default_rng(3)
    for q, qd, force in zip(*_stance_states(rng, body, 20)):
        qd[0] = 0.0  # the rigid leg is only meaningful with wd = 0 (ERRATA 3)
        M, rhs = _locked_stance_system(body, q, qd, force)
        np.testing.assert_array_equal(M[0], [1, 0, 0])
        np.testing.assert_array_equal(M[:, 0], [1, 0, 0])
        assert rhs[0] == 0
        A, B = printed_a1(body, q, qd, force)
        acc = stance_accelerations(body, q, qd, force, locked=True)
        assert acc[0] == 0
        _close(acc[1:], np.linalg.solve(A[1:, 1:], B[1:]), 1e3 * np.abs(acc).max())


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_locked_knee_eq_5(body):
    """a22 = 1, b2 = a12 = a21 = 0: theta4dd = 0 and theta3dd = b1 / a11."""
    rng = np.random.default_rng(4)
    for q, qd, force, hip_acc in zip(*_swing_states(rng, 20)):
        qd[1] = 0.0
        A, B = printed_a2(body, q, qd, hip_acc, force)
        acc = swing_accelerations(body, q, qd, force, hip_acc, locked=True)
        assert acc[1] == 0
        _close(acc[0], B[0] / A[0, 0], 1e3 * abs(acc[0]))


def test_hip_kinematics_equal_printed_a2_first_display():
    rng = np.random.default_rng(5)
    for _ in range(20):
        w, t1, wd, t1d, wdd, t1dd = rng.uniform(0.5, 1.0), *rng.uniform(-3, 3, 5)
        s, c = np.sin(t1), np.cos(t1)
        pos, vel, acc = hip_kinematics(BODIES[0], [w, t1, 0.3], [wd, t1d, 0.1], [wdd, t1dd, 0.2])
        _close(pos, [w * s, w * c], 1.0)
        _close(vel, [wd * s + w * t1d * c, wd * c - w * t1d * s], 10.0)
        _close(acc, [wdd * s + 2 * wd * t1d * c + w * (t1dd * c - t1d ** 2 * s),
                     wdd * c - 2 * wd * t1d * s - w * (t1dd * s + t1d ** 2 * c)], 100.0)


# ---- mirror symmetry: theta -> -theta, x -> -x -----------------------------------------------

@pytest.mark.parametrize("locked", [False, True])
def test_stance_mirror_symmetry(locked):
    body = BODIES[0]
    rng = np.random.default_rng(6)
    flip = np.array([1.0, -1.0, -1.0])  # w is a length; the angles change sign
    for q, qd, force in zip(*_stance_states(rng, body, 20)):
        if locked:
            qd[0] = 0.0
        acc = stance_accelerations(body, q, qd, force, locked)
        mirrored = stance_accelerations(body, flip * q, flip * qd, flip * force, locked)
        _close(mirrored, flip * acc, 1e3 * np.abs(acc).max())
        pos, vel, hip_acc = hip_kinematics(body, q, qd, acc)
        pos_m, vel_m, hip_acc_m = hip_kinematics(body, flip * q, flip * qd, mirrored)
        xflip = np.array([-1.0, 1.0])
        for a, b in ((pos, pos_m), (vel, vel_m), (hip_acc, hip_acc_m)):
            _close(b, xflip * a, 1e3 * np.abs(a).max())


@pytest.mark.parametrize("locked", [False, True])
def test_swing_mirror_symmetry(locked):
    body = BODIES[1]
    rng = np.random.default_rng(7)
    xflip = np.array([-1.0, 1.0])
    for q, qd, force, hip_acc in zip(*_swing_states(rng, 20)):
        acc = swing_accelerations(body, q, qd, force, hip_acc, locked)
        mirrored = swing_accelerations(body, -q, -qd, -force, xflip * hip_acc, locked)
        _close(mirrored, -acc, 1e3 * np.abs(acc).max())
        # and the mirror is not trivial: the unmirrored hip acceleration gives another answer
        if abs(hip_acc[0]) > 1:
            other = swing_accelerations(body, -q, -qd, -force, hip_acc, locked)
            assert np.abs(other + acc).max() > 1e-6


# ---- numeric API argument checks ----------------------------------------------------------------

@pytest.mark.parametrize("call", [
    lambda b: stance_accelerations(b, [1, 0], [0, 0, 0], [0, 0, 0]),
    lambda b: stance_accelerations(b, [1, 0, 0], [0, 0, 0], [0, 0, np.nan]),
    lambda b: stance_accelerations(b, [1, 0, 0], [0, 0, 0], [0, 0, 0], locked=2),
    lambda b: swing_accelerations(b, [0, 0], [0, 0], [0, 0], [0, 0, 0]),
    lambda b: swing_accelerations(b, [0, 0], [0, 0], "x", [0, 0]),
    lambda b: stance_accelerations("body", [1, 0, 0], [0, 0, 0], [0, 0, 0]),
])
def test_api_rejects_bad_arguments_with_config_error(call):
    with pytest.raises(ConfigError, match="got"):
        call(Body(1.8, 80.0))
