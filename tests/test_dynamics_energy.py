"""Energy balance of the derived models (Appendix A), integrated with DOP853 at rtol = atol = 1e-12.

Drift is measured against the largest kinetic energy of the run, which does not depend on the
arbitrary datum of the potential energy (so a drift cannot hide behind a large V).
"""
from __future__ import annotations

import numpy as np
import pytest

from _dynamics_support import (BODIES, integrate, printed_a2, spring_energy, stance_rhs_function,
                               swing_rhs_function)
from klaw_ocp.dynamics import stance_energy, swing_energy

DRIFT = 1e-8


def _drift(kinetic, potential):
    total = kinetic + potential
    return np.abs(total - total[0]).max() / kinetic.max()


def _stance_energies(body, X, **springs):
    TV = np.array([stance_energy(body, x[:3], x[3:]) for x in X])
    return TV[:, 0], TV[:, 1] + np.array([spring_energy(x, **springs) for x in X])


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_stance_with_conservative_springs_conserves_energy(body):
    """Telescopic leg on a spring F_w = -k (w - l1) plus a hip spring between leg and upper body:
    checks the mass matrix against T, and that F enters as +F, conjugate to w, theta1, theta2."""
    springs = dict(k_w=25.0 * body.mass * body.g / body.l1, l_rest=body.l1, k_hip=3 * body.m2 * body.g * body.r2)
    rhs = stance_rhs_function(body, **springs)
    x0 = [0.97 * body.l1, 0.2, 0.05, 0.3, -0.8, -0.3]
    _, X = integrate(lambda t, x: np.asarray(rhs(x)).ravel(), x0, 1.0)
    assert np.ptp(X[:, 0]) > 0.03 * body.l1 and np.ptp(X[:, 1]) > 0.3  # it really moves
    assert _drift(*_stance_energies(body, X, **springs)) < DRIFT


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_rigid_stance_leg_conserves_energy(body):
    """The locked (rigid) leg, F = 0, started with wd = 0: a falling inverted double pendulum."""
    rhs = stance_rhs_function(body, locked=1)
    x0 = [body.l1, 0.2, 0.05, 0.0, -0.8, -0.3]
    _, X = integrate(lambda t, x: np.asarray(rhs(x)).ravel(), x0, 1.0)
    assert np.all(X[:, 0] == body.l1) and np.all(X[:, 3] == 0)
    assert np.ptp(X[:, 1]) > 0.3
    assert _drift(*_stance_energies(body, X)) < DRIFT


def test_rigid_stance_leg_needs_the_lock_map():
    """With wd != 0 the locked equations keep w moving at constant rate and energy is not
    conserved: why the lock maps (impacts.py) zero wd before the rigid subphase starts.

    Constant rate: wdd = 0, so wd stays 0.3 m/s and w = l1 + 0.3 t. DOP853 (like any Runge-Kutta
    method) integrates a constant derivative exactly, so only round-off separates w from the line
    (measured 3e-16); the tolerances are far below any real acceleration of w over 1 s (a wdd of
    1e-6 m/s^2 would already put w 5e-7 m off the line)."""
    body, wd0 = BODIES[0], 0.3
    rhs = stance_rhs_function(body, locked=1)
    t, X = integrate(lambda t, x: np.asarray(rhs(x)).ravel(), [body.l1, 0.2, 0.05, wd0, -0.8, -0.3], 1.0)
    assert t[-1] == pytest.approx(1.0) and np.ptp(X[:, 1]) > 0.3          # the pendulum really falls
    assert np.abs(X[:, 3] - wd0).max() < 1e-10
    assert np.abs(X[:, 0] - (body.l1 + wd0 * t)).max() < 1e-10
    assert _drift(*_stance_energies(body, X)) > 1e-2


def _swing_run(body, x0, locked=0, t_end=1.5, hip=(0.0, 1.0)):
    rhs = swing_rhs_function(body, locked)
    _, X = integrate(lambda t, x: np.asarray(rhs(x, [0.0, 0.0])).ravel(), x0, t_end)
    TV = np.array([swing_energy(body, x[:2], x[2:], hip, [0.0, 0.0]) for x in X])
    return X, TV[:, 0], TV[:, 1]


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_swing_with_fixed_hip_conserves_energy(body):
    X, T, V = _swing_run(body, [-0.4, 0.9, 1.0, -2.0])
    assert np.ptp(X[:, 0]) > 0.5 and np.ptp(X[:, 1]) > 0.5
    assert _drift(T, V) < DRIFT


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_locked_knee_swing_conserves_energy(body):
    X, T, V = _swing_run(body, [-0.4, 0.6, 2.5, 0.0], locked=1)
    assert np.all(X[:, 1] == 0.6) and np.ptp(X[:, 0]) > 0.5
    assert _drift(T, V) < DRIFT


def test_printed_a2_typo_breaks_energy_conservation():
    """ERRATA 2: the printed Coriolis term (theta4 for theta4d) makes a passive swing drift by far
    more than 1e-2 in 2 s, while the corrected transcription conserves energy to 1e-8."""
    body = BODIES[0]
    for typo, check in ((True, lambda d: d > 1e-2), (False, lambda d: d < DRIFT)):
        def rhs(t, x, typo=typo):
            A, B = printed_a2(body, x[:2], x[2:], (0.0, 0.0), typo=typo)
            return np.concatenate([x[2:], np.linalg.solve(A, B)])
        _, X = integrate(rhs, [-0.4, 0.9, 1.0, -2.0], 2.0)
        TV = np.array([swing_energy(body, x[:2], x[2:], [0.0, 1.0], [0.0, 0.0]) for x in X])
        assert check(_drift(TV[:, 0], TV[:, 1])), f"typo={typo}"


def _rotation_dd(angle, rate, acc):
    """Second derivative of (sin a, cos a)."""
    return acc * np.array([np.cos(angle), -np.sin(angle)]) - rate ** 2 * np.array([np.sin(angle), np.cos(angle)])


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_swing_energy_change_equals_hip_work(body):
    """Prescribed hip x_h = A sin(wt), y_h = y0 + B cos(wt): T + V changes by exactly the work of
    the force the hip applies to the leg, F_hip = dP/dt + (m3 + m4) g e_y (Newton, computed here
    from the centre-of-mass accelerations, independently of the Lagrangian)."""
    amp_x, amp_y, omega, y0 = 0.15, 0.05, 3 * np.pi, 0.95 * body.l1

    def hip(t):
        s, c = np.sin(omega * t), np.cos(omega * t)
        return (np.array([amp_x * s, y0 + amp_y * c]), omega * np.array([amp_x * c, -amp_y * s]),
                -omega ** 2 * np.array([amp_x * s, amp_y * c]))

    rhs = swing_rhs_function(body)

    def augmented(t, z):
        _, vel, acc = hip(t)
        xd = np.asarray(rhs(z[:4], acc)).ravel()
        (t3, t4, t3d, t4d), (t3dd, t4dd) = z[:4], xd[2:]
        thigh = _rotation_dd(t3, t3d, t3dd)
        a3 = acc - body.r3 * thigh
        a4 = acc - body.l3 * thigh - body.r4 * _rotation_dd(t3 + t4, t3d + t4d, t3dd + t4dd)
        f_hip = body.m3 * a3 + body.m4 * a4 + np.array([0.0, (body.m3 + body.m4) * body.g])
        return np.concatenate([xd, [f_hip @ vel]])

    times, Z = integrate(augmented, [-0.3, 0.5, 1.0, -1.0, 0.0], 1.5)
    energy = np.array([sum(swing_energy(body, z[:2], z[2:4], *hip(t)[:2])) for t, z in zip(times, Z)])
    work = Z[:, 4]
    assert np.abs(work).max() > 0.1 * np.ptp(energy)  # the hip really does work
    assert np.abs(energy - energy[0] - work).max() < 1e-8 * np.abs(work).max()
