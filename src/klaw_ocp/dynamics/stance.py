"""Stance model, figure 2a and Appendix A.1: a telescopic inverted pendulum with an upper body.

Coordinates ``q = [w, theta1, theta2]`` (m, rad, rad), rates ``qd`` likewise per second; the state
vector is ``x = [w, theta1, theta2, wd, theta1d, theta2d]``. Generalized forces
``F = [F_w (N), F_theta1 (N m), F_theta2 (N m)]``, conjugate to those coordinates.

Conventions (ERRATA "Conventions"): x forward, y up, gravity -y. The ankle (the "dynamic foot")
is fixed at the stance origin; ``hip = ankle + w (sin theta1, cos theta1)``, so theta1 > 0 puts the
hip ahead of the ankle. The leg is one rigid body (m1, I1) with its centre of mass at the
constant distance r1 from the ankle; the telescoping part is massless. The upper-body centre of
mass is ``hip + r2 (sin theta2, cos theta2)``.

The rigid (locked) leg of section 4.2 is the Lagrangian with w held constant: row and column 1 of
the mass matrix become (1, 0, 0) and b1 = 0, hence wdd = 0 (ERRATA 3). ``locked`` is a number
(0 or 1) so one symbolic expression serves both variants.
"""
from __future__ import annotations

import casadi as ca

from ..casadi_builds import built_once
from .lagrange import lagrange_mass_bias, point_velocity
from .parameters import N_BODY_PARAMETERS, body_symbols

N_Q = 3


def _unit(angle):
    return ca.vertcat(ca.sin(angle), ca.cos(angle))


def stance_points(q, p) -> dict:
    """Positions relative to the ankle: ``hip``, ``leg_com`` and ``trunk_com`` (2-vectors)."""
    s = body_symbols(p)
    w, th1, th2 = q[0], q[1], q[2]
    hip = w * _unit(th1)
    return {"hip": hip, "leg_com": s.r1 * _unit(th1), "trunk_com": hip + s.r2 * _unit(th2)}


def stance_energies(q, qd, p):
    """Kinetic and potential energy (J) of the stance model; potential zero at ankle height."""
    s = body_symbols(p)
    pts = stance_points(q, p)
    v1 = point_velocity(pts["leg_com"], q, qd)
    v2 = point_velocity(pts["trunk_com"], q, qd)
    kinetic = (0.5 * s.m1 * ca.dot(v1, v1) + 0.5 * s.I1 * qd[1] ** 2
               + 0.5 * s.m2 * ca.dot(v2, v2) + 0.5 * s.I2 * qd[2] ** 2)
    potential = s.g * (s.m1 * pts["leg_com"][1] + s.m2 * pts["trunk_com"][1])
    return kinetic, potential


def stance_mass_bias(q, qd, p):
    """``M(q)`` and ``b(q, qd)`` with ``M qdd = b + F`` (Appendix A.1's A and B minus the forces)."""
    qdd = ca.SX.sym("qdd", N_Q)
    kinetic, potential = stance_energies(q, qd, p)
    mass, bias = lagrange_mass_bias(kinetic, potential, q, qd, qdd, N_Q)
    return mass, bias


def apply_lock(mass, rhs, locked, index: int):
    """Constrain coordinate ``index`` to zero acceleration when ``locked`` is 1 (section 4.2, eq. 5)."""
    n = mass.shape[0]
    keep = ca.SX.ones(n)
    keep[index] = 1 - locked
    sel = ca.diag(keep)
    unit = ca.SX.zeros(n)
    unit[index] = 1
    return sel @ mass @ sel + locked * (unit @ unit.T), sel @ rhs


@built_once
def _mass_bias_function() -> ca.Function:
    q, qd, p = ca.SX.sym("q", N_Q), ca.SX.sym("qd", N_Q), ca.SX.sym("p", N_BODY_PARAMETERS)
    return ca.Function("stance_mass_bias", [q, qd, p], [*stance_mass_bias(q, qd, p)])


def stance_accelerations_sx(q, qd, force, p, locked=0):
    """``qdd`` of the stance model; ``locked`` = 1 gives the rigid leg (wdd = 0).

    Works on any SX expressions (the derivation itself needs pure symbols, so it goes through
    a Function built once)."""
    mass, bias = _mass_bias_function()(q, qd, p)
    mass, rhs = apply_lock(mass, bias + force, locked, 0)
    return ca.solve(mass, rhs)


def hip_kinematics_sx(q, qd, qdd):
    """Hip position, velocity and acceleration relative to the ankle (Appendix A.2, first display)."""
    w, th1 = q[0], q[1]
    pos = w * _unit(th1)
    vel = ca.jtimes(pos, q, qd)
    acc = ca.jtimes(vel, q, qd) + ca.jtimes(vel, qd, qdd)
    return pos, vel, acc


@built_once
def stance_functions() -> dict:
    """CasADi Functions of the stance model, built once per process.

    ``mass_bias(q, qd, p) -> (M, b)``; ``acc(q, qd, F, p, locked) -> qdd``;
    ``energy(q, qd, p) -> (T, V)``; ``hip(q, qd, qdd) -> (pos, vel, acc)``;
    ``points(q, p) -> (hip, leg_com, trunk_com)``.
    """
    q, qd, qdd = ca.SX.sym("q", N_Q), ca.SX.sym("qd", N_Q), ca.SX.sym("qdd", N_Q)
    force, p, locked = ca.SX.sym("F", N_Q), ca.SX.sym("p", N_BODY_PARAMETERS), ca.SX.sym("locked")
    mass, bias = stance_mass_bias(q, qd, p)
    kinetic, potential = stance_energies(q, qd, p)
    pts = stance_points(q, p)
    hip_pos, hip_vel, hip_acc = hip_kinematics_sx(q, qd, qdd)
    return {
        "mass_bias": ca.Function("stance_mass_bias", [q, qd, p], [mass, bias], ["q", "qd", "p"], ["M", "b"]),
        "acc": ca.Function("stance_acc", [q, qd, force, p, locked],
                           [stance_accelerations_sx(q, qd, force, p, locked)],
                           ["q", "qd", "F", "p", "locked"], ["qdd"]),
        "energy": ca.Function("stance_energy", [q, qd, p], [kinetic, potential], ["q", "qd", "p"], ["T", "V"]),
        "hip": ca.Function("stance_hip", [q, qd, qdd], [hip_pos, hip_vel, hip_acc],
                           ["q", "qd", "qdd"], ["pos", "vel", "acc"]),
        "points": ca.Function("stance_points", [q, p], [pts["hip"], pts["leg_com"], pts["trunk_com"]],
                              ["q", "p"], ["hip", "leg_com", "trunk_com"]),
    }
