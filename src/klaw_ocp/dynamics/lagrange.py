"""Lagrange's equations, derived symbolically (Appendix A, first display).

One routine serves both models: given the kinetic energy T and potential energy V of a system in
the coordinates ``q`` (some of which may have a prescribed motion, like the swing model's hip),
it returns the mass matrix and bias of the equations of the *free* coordinates,

    d/dt(dL/dqd_r) - dL/dq_r = F_r        <=>        M(q) qdd_free = b(q, qd, qdd_prescribed) + F,

where ``L = T - V``. Nothing is transcribed from the appendix: the tests compare the result with
the printed matrices instead.
"""
from __future__ import annotations

import casadi as ca


def lagrange_mass_bias(T: ca.SX, V: ca.SX, q: ca.SX, qd: ca.SX, qdd: ca.SX, n_free: int):
    """Mass matrix ``M`` (n_free x n_free) and bias ``b`` (n_free) of Lagrange's equations.

    ``q``, ``qd`` and ``qdd`` stack the free coordinates first and the prescribed ones after. The
    bias contains gravity, Coriolis/centrifugal terms and the inertial effect of the prescribed
    accelerations ``qdd[n_free:]``; the generalized forces are *not* included.
    """
    lagrangian = T - V
    dl_dqd = ca.gradient(lagrangian, qd)
    # d/dt (dL/dqd) = (d dL/dqd / dqd) qdd + (d dL/dqd / dq) qd  (no explicit time dependence)
    euler_lagrange = (ca.jtimes(dl_dqd, qd, qdd) + ca.jtimes(dl_dqd, q, qd)
                      - ca.gradient(lagrangian, q))
    residual = euler_lagrange[:n_free]
    qdd_free = qdd[:n_free]
    mass = ca.jacobian(residual, qdd_free)
    bias = -ca.substitute(residual, qdd_free, ca.SX.zeros(n_free))
    return ca.simplify(mass), ca.simplify(bias)


def point_velocity(position: ca.SX, q: ca.SX, qd: ca.SX) -> ca.SX:
    """Velocity of a point given as a function of the coordinates: J(q) qd."""
    return ca.jtimes(position, q, qd)
