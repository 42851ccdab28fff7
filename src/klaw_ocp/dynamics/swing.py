"""Swing model, figure 2b and Appendix A.2: a double pendulum hanging from a moving hip.

Coordinates ``q = [theta3, theta4]`` (rad), rates ``qd`` (rad/s); state
``x = [theta3, theta4, theta3d, theta4d]``. Generalized forces ``F = [F_theta3, F_theta4]`` (N m).
The hip position ``(x_h, y_h)`` is an input, prescribed by the stance model (assumption 4).

Conventions (ERRATA "Conventions"): ``knee = hip - l3 (sin theta3, cos theta3)`` and
``ankle = knee - l4 (sin(theta3+theta4), cos(theta3+theta4))``. theta3 has the sense of theta1, so a
foot ahead of the hip gives theta3 < 0; theta4 > 0 is knee flexion.

The locked knee (eq. 5): a22 = 1, b2 = a12 = a21 = 0, i.e. theta4dd = 0.
"""
from __future__ import annotations

import casadi as ca

from ..casadi_builds import built_once
from .lagrange import lagrange_mass_bias, point_velocity
from .parameters import N_BODY_PARAMETERS, body_symbols
from .stance import apply_lock

N_Q = 2


def _down(angle):
    return -ca.vertcat(ca.sin(angle), ca.cos(angle))


def swing_points(q, hip, p) -> dict:
    """World positions of ``hip``, ``knee``, ``ankle``, ``thigh_com`` and ``shank_com``."""
    s = body_symbols(p)
    th3, th4 = q[0], q[1]
    knee = hip + s.l3 * _down(th3)
    return {"hip": hip, "knee": knee, "ankle": knee + s.l4 * _down(th3 + th4),
            "thigh_com": hip + s.r3 * _down(th3), "shank_com": knee + s.r4 * _down(th3 + th4)}


def swing_energies(q, qd, hip, hip_vel, p):
    """Kinetic and potential energy (J) of the swing leg; potential zero at y = 0 (the ground)."""
    s = body_symbols(p)
    coords, rates = ca.vertcat(q, hip), ca.vertcat(qd, hip_vel)
    pts = swing_points(q, hip, p)
    v3 = point_velocity(pts["thigh_com"], coords, rates)
    v4 = point_velocity(pts["shank_com"], coords, rates)
    kinetic = (0.5 * s.m3 * ca.dot(v3, v3) + 0.5 * s.I3 * qd[0] ** 2
               + 0.5 * s.m4 * ca.dot(v4, v4) + 0.5 * s.I4 * (qd[0] + qd[1]) ** 2)
    potential = s.g * (s.m3 * pts["thigh_com"][1] + s.m4 * pts["shank_com"][1])
    return kinetic, potential


def swing_mass_bias(q, qd, hip_acc, p):
    """``M(q)`` and ``b(q, qd, hip_acc)`` with ``M qdd = b + F`` (Appendix A.2 minus the forces).

    The hip is handled as two extra coordinates with a prescribed motion; only the hip
    acceleration enters the equations (its position and velocity cancel out).
    """
    hip, hip_vel = ca.SX.sym("hip", 2), ca.SX.sym("hip_vel", 2)
    qdd = ca.SX.sym("qdd", N_Q)
    kinetic, potential = swing_energies(q, qd, hip, hip_vel, p)
    mass, bias = lagrange_mass_bias(kinetic, potential, ca.vertcat(q, hip), ca.vertcat(qd, hip_vel),
                                    ca.vertcat(qdd, hip_acc), N_Q)
    # The hip position and velocity cancel analytically; substituting zero removes the leftovers
    # that simplify() does not collect.
    zero = ca.SX.zeros(2)
    mass, bias = (ca.substitute(e, ca.vertcat(hip, hip_vel), ca.vertcat(zero, zero)) for e in (mass, bias))
    return ca.simplify(mass), ca.simplify(bias)


@built_once
def _mass_bias_function() -> ca.Function:
    q, qd = ca.SX.sym("q", N_Q), ca.SX.sym("qd", N_Q)
    hip_acc, p = ca.SX.sym("hip_acc", 2), ca.SX.sym("p", N_BODY_PARAMETERS)
    return ca.Function("swing_mass_bias", [q, qd, hip_acc, p], [*swing_mass_bias(q, qd, hip_acc, p)])


def swing_accelerations_sx(q, qd, force, hip_acc, p, locked=0):
    """``qdd`` of the swing model; ``locked`` = 1 gives the locked knee of eq. 5 (theta4dd = 0).

    Works on any SX expressions (via a Function built once, like the stance model)."""
    mass, bias = _mass_bias_function()(q, qd, hip_acc, p)
    mass, rhs = apply_lock(mass, bias + force, locked, 1)
    return ca.solve(mass, rhs)


@built_once
def swing_functions() -> dict:
    """CasADi Functions of the swing model, built once per process.

    ``mass_bias(q, qd, hip_acc, p) -> (M, b)``; ``acc(q, qd, F, hip_acc, p, locked) -> qdd``;
    ``energy(q, qd, hip, hip_vel, p) -> (T, V)``; ``points(q, hip, p) -> (knee, ankle)``.
    """
    q, qd, force = ca.SX.sym("q", N_Q), ca.SX.sym("qd", N_Q), ca.SX.sym("F", N_Q)
    hip, hip_vel, hip_acc = ca.SX.sym("hip", 2), ca.SX.sym("hip_vel", 2), ca.SX.sym("hip_acc", 2)
    p, locked = ca.SX.sym("p", N_BODY_PARAMETERS), ca.SX.sym("locked")
    mass, bias = swing_mass_bias(q, qd, hip_acc, p)
    kinetic, potential = swing_energies(q, qd, hip, hip_vel, p)
    pts = swing_points(q, hip, p)
    return {
        "mass_bias": ca.Function("swing_mass_bias", [q, qd, hip_acc, p], [mass, bias],
                                 ["q", "qd", "hip_acc", "p"], ["M", "b"]),
        "acc": ca.Function("swing_acc", [q, qd, force, hip_acc, p, locked],
                           [swing_accelerations_sx(q, qd, force, hip_acc, p, locked)],
                           ["q", "qd", "F", "hip_acc", "p", "locked"], ["qdd"]),
        "energy": ca.Function("swing_energy", [q, qd, hip, hip_vel, p], [kinetic, potential],
                              ["q", "qd", "hip", "hip_vel", "p"], ["T", "V"]),
        "points": ca.Function("swing_points", [q, hip, p], [pts["knee"], pts["ankle"]],
                              ["q", "hip", "p"], ["knee", "ankle"]),
    }
