"""Numeric public API of the dynamics (section 2.3, Appendix A): numpy in, numpy out.

Thin wrappers over the cached CasADi Functions of :mod:`.stance` and :mod:`.swing`, for users,
plots and tests. Solvers should use the Functions or the ``*_sx`` builders directly.

Conventions (ERRATA "Conventions"; see :mod:`.stance`, :mod:`.swing`): x forward, y up, SI units.

- Stance: ``q = [w, theta1, theta2]`` (m, rad, rad), ``F = [F_w, F_theta1, F_theta2]`` (N, N m, N m),
  positions relative to the fixed ankle.
- Swing: ``q = [theta3, theta4]`` (rad), ``F = [F_theta3, F_theta4]`` (N m); the hip position,
  velocity and acceleration (world frame, 2-vectors) are prescribed inputs.
- Every model satisfies ``M(q) qdd = b(q, qd[, hip_acc]) + F``. ``locked=True`` gives the rigid stance
  leg (wdd = 0, section 4.2 / ERRATA 3) or the locked knee (theta4dd = 0, eq. 5); the full
  acceleration vector is returned with 0 for the locked coordinate.
"""
from __future__ import annotations

import numpy as np

from ._checks import as_flag, as_vector, check_body, to_numpy
from .stance import stance_functions
from .swing import swing_functions


def stance_accelerations(body, q, qd, F, locked=False) -> np.ndarray:
    """``[wdd, theta1dd, theta2dd]`` of the stance model (Appendix A.1)."""
    body = check_body(body)
    out = stance_functions()["acc"](as_vector("q", q, 3), as_vector("qd", qd, 3), as_vector("F", F, 3),
                                    body.dynamic_parameters(), as_flag("locked", locked))
    return to_numpy(out)


def swing_accelerations(body, q, qd, F, hip_acc, locked=False) -> np.ndarray:
    """``[theta3dd, theta4dd]`` of the swing model driven by ``hip_acc = [xdd_h, ydd_h]`` (Appendix A.2)."""
    body = check_body(body)
    out = swing_functions()["acc"](as_vector("q", q, 2), as_vector("qd", qd, 2), as_vector("F", F, 2),
                                   as_vector("hip_acc", hip_acc, 2), body.dynamic_parameters(),
                                   as_flag("locked", locked))
    return to_numpy(out)


def stance_mass_matrix(body, q) -> np.ndarray:
    """The 3x3 mass matrix ``M(q)`` of the stance model (Appendix A.1's A)."""
    body = check_body(body)
    mass, _ = stance_functions()["mass_bias"](as_vector("q", q, 3), np.zeros(3), body.dynamic_parameters())
    return np.asarray(mass, dtype=float)


def stance_bias(body, q, qd) -> np.ndarray:
    """The right-hand side ``b(q, qd)`` of the stance model without the generalized forces."""
    body = check_body(body)
    _, bias = stance_functions()["mass_bias"](as_vector("q", q, 3), as_vector("qd", qd, 3),
                                              body.dynamic_parameters())
    return to_numpy(bias)


def swing_mass_matrix(body, q) -> np.ndarray:
    """The 2x2 mass matrix ``M(q)`` of the swing model (Appendix A.2's A)."""
    body = check_body(body)
    mass, _ = swing_functions()["mass_bias"](as_vector("q", q, 2), np.zeros(2), np.zeros(2),
                                             body.dynamic_parameters())
    return np.asarray(mass, dtype=float)


def swing_bias(body, q, qd, hip_acc) -> np.ndarray:
    """The right-hand side ``b(q, qd, hip_acc)`` of the swing model without the generalized forces."""
    body = check_body(body)
    _, bias = swing_functions()["mass_bias"](as_vector("q", q, 2), as_vector("qd", qd, 2),
                                             as_vector("hip_acc", hip_acc, 2), body.dynamic_parameters())
    return to_numpy(bias)


def stance_energy(body, q, qd):
    """Kinetic and potential energy ``(T, V)`` in J of the stance model (V = 0 at ankle height)."""
    body = check_body(body)
    kinetic, potential = stance_functions()["energy"](as_vector("q", q, 3), as_vector("qd", qd, 3),
                                                      body.dynamic_parameters())
    return float(kinetic), float(potential)


def swing_energy(body, q, qd, hip, hip_vel):
    """Kinetic and potential energy ``(T, V)`` in J of the swing leg (world frame, V = 0 at y = 0)."""
    body = check_body(body)
    kinetic, potential = swing_functions()["energy"](as_vector("q", q, 2), as_vector("qd", qd, 2),
                                                     as_vector("hip", hip, 2), as_vector("hip_vel", hip_vel, 2),
                                                     body.dynamic_parameters())
    return float(kinetic), float(potential)


def hip_kinematics(body, q, qd, qdd):
    """Hip ``(pos, vel, acc)`` relative to the stance ankle (Appendix A.2, first display).

    ``body`` is not needed (the hip depends on w and theta1 only) and is taken for symmetry.
    """
    check_body(body)
    pos, vel, acc = stance_functions()["hip"](as_vector("q", q, 3), as_vector("qd", qd, 3),
                                              as_vector("qdd", qdd, 3))
    return to_numpy(pos), to_numpy(vel), to_numpy(acc)
