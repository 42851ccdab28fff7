"""Heel-strike map (section 4, "conservation of linear and angular momentum") and lock maps
(sections 4.2 and 4.3, eq. 5; ERRATA "Open choices").

States: stance ``x = [w, theta1, theta2, wd, theta1d, theta2d]`` relative to its ankle (see
:mod:`.stance`); swing ``x = [theta3, theta4, theta3d, theta4d]`` (see :mod:`.swing`). Units m, rad, s.

Heel strike -- the rule chosen here
-----------------------------------
The paper says only that the new stance initial conditions follow from "the conservation of
linear and angular momentum". We take: **the telescope is massless and carries no impulse**.
A massless telescope cannot transmit an impulsive force (it would give it infinite acceleration),
so nothing impulsive acts on the upper body at impact. Hence, across heel strike,

- the hip position and the hip velocity are continuous (world frame),
- theta2 and theta2d are continuous,

and therefore the upper body's linear momentum ``m2 v_com2``, its spin ``I2 theta2d`` about its
centre of mass and its angular momentum about the new ankle are all conserved.
Given the offset ``(dx, dy)`` of the new ankle from the old one (both ankles are at height l9 in
the walk, so dy = 0), with ``h`` the hip relative to the new ankle and ``v`` the hip velocity:

    w' = |h|,   theta1' = atan2(h_x, h_y),   wd' = v . e',   w' theta1d' = v . e_perp',
    e' = (sin theta1', cos theta1'),   e_perp' = (cos theta1', -sin theta1').

What is **not** conserved: the stance leg's angular momentum about the new ankle (the old leg's
and the new leg's are different bodies, and the new one starts rotating at the rate the hip
velocity imposes), and hence the whole stance model's.

Why not conserve the whole model's angular momentum about the new ankle (ERRATA's other
candidate)? Assumption 4 splits the models: the swing leg's mass is not in the stance model, so
the "whole model" before impact is the old leg plus the upper body, and after impact a different
leg plus the upper body -- not one mechanical system whose momentum an impulse at the ankle
would preserve. Imposing it would need an impulse through the massless telescope, which is
inconsistent. The hip-velocity rule is the one consistent with a massless telescope, and it keeps
the hip's vertical sinusoid (section 4.2) continuous from step to step.

Angular momenta are reported in the sense of the paper's angles (clockwise positive, so a body
spinning with rate ``theta2d`` has spin ``+I2 theta2d``): ``H = sum m (r - a) x_cw v + I thetad``
with ``a x_cw b = a_y b_x - a_x b_y``.

Lock maps
---------
When the stance leg locks (wd -> 0, section 4.2) or the knee locks (theta4d -> 0, eq. 5):

- ``rule="zero"``: the paper -- only the locked rate is set to zero.
- ``rule="momentum"`` (default): an impulse acts in the locked coordinate only, so every other
  generalized momentum is conserved. Solve ``[[M, -e_i], [e_i^T, 0]] [qd+; L] = [M qd-; 0]``.
  It is the M-orthogonal projection of the rates, so the kinetic energy cannot increase (with a
  fixed hip for the swing). For the swing leg the generalized momentum ``dT/dtheta3d`` also holds
  a term linear in the hip velocity; that velocity is prescribed (continuous), so the term is the
  same before and after and M alone suffices.
"""
from __future__ import annotations

import casadi as ca
import numpy as np

from .. import choices
from ..casadi_builds import built_once
from ..errors import ConfigError, out_of_range
from ._checks import as_vector, check_body, choice
from .evaluate import evaluate
from .parameters import N_BODY_PARAMETERS
from .stance import stance_mass_bias
from .swing import swing_mass_bias

#: Accepted values of the ``rule`` argument of the lock maps (the first is the default).
LOCK_RULES = choices.LOCK_RULES

#: Keys of :func:`heel_strike_conserved` that the heel-strike map conserves, and those it does not.
CONSERVED = ("hip", "hip_velocity", "upper_body_momentum", "upper_body_spin",
             "upper_body_angular_momentum")
NOT_CONSERVED = ("leg_angular_momentum", "total_angular_momentum")


# ---- symbolic cores (SX in, SX out; also work on DM) ----------------------------------------

def heel_strike_map_sx(x_pre, new_ankle_offset):
    """Post-impact stance state from the pre-impact one (the rule of the module docstring)."""
    w, th1, th2, wd, th1d, th2d = (x_pre[i] for i in range(6))
    e = ca.vertcat(ca.sin(th1), ca.cos(th1))
    e_perp = ca.vertcat(ca.cos(th1), -ca.sin(th1))
    hip = w * e - ca.vertcat(new_ankle_offset[0], new_ankle_offset[1])
    vel = wd * e + w * th1d * e_perp
    w_new = ca.sqrt(ca.dot(hip, hip))
    th1_new = ca.atan2(hip[0], hip[1])
    e_new = ca.vertcat(ca.sin(th1_new), ca.cos(th1_new))
    e_perp_new = ca.vertcat(ca.cos(th1_new), -ca.sin(th1_new))
    return ca.vertcat(w_new, th1_new, th2, ca.dot(vel, e_new), ca.dot(vel, e_perp_new) / w_new, th2d)


def momentum_lock_sx(mass, qd, index: int):
    """Rates after an impulse in coordinate ``index`` that brings its rate to zero, every other
    generalized momentum ``(M qd)_j`` unchanged (the KKT system of the module docstring).

    The KKT system is solved in its reduced form -- rows j != index of ``M qd+ = M qd-`` with
    ``qd+_index = 0`` -- so that the locked rate comes out exactly zero, not 1e-14.
    """
    n = mass.shape[0]
    free = [j for j in range(n) if j != index]
    momentum = mass @ qd
    qd_free = ca.solve(mass[free, free], momentum[free])
    out = [None] * n
    out[index] = 0
    for k, j in enumerate(free):
        out[j] = qd_free[k]
    return ca.vertcat(*out)


@built_once
def impact_functions() -> dict:
    """CasADi Functions of the maps, built once: ``heel_strike(x, offset) -> x_post``,
    ``stance_lock(x, p) -> x_post`` and ``knee_lock(x, p) -> x_post`` (momentum rule)."""
    xs, xw = ca.SX.sym("x", 6), ca.SX.sym("x", 4)
    offset, p = ca.SX.sym("offset", 2), ca.SX.sym("p", N_BODY_PARAMETERS)
    m_stance, _ = stance_mass_bias(xs[:3], xs[3:], p)
    m_swing, _ = swing_mass_bias(xw[:2], xw[2:], ca.SX.zeros(2), p)
    return {
        "heel_strike": ca.Function("heel_strike", [xs, offset], [heel_strike_map_sx(xs, offset)],
                                   ["x", "offset"], ["x_post"]),
        "stance_lock": ca.Function("stance_lock", [xs, p],
                                   [ca.vertcat(xs[:3], momentum_lock_sx(m_stance, xs[3:], 0))],
                                   ["x", "p"], ["x_post"]),
        "knee_lock": ca.Function("knee_lock", [xw, p],
                                 [ca.vertcat(xw[:2], momentum_lock_sx(m_swing, xw[2:], 1))],
                                 ["x", "p"], ["x_post"]),
    }


# ---- numeric API -----------------------------------------------------------------------------

def heel_strike_map(body, x_pre, new_ankle_offset, hip_shift=(0.0, 0.0)) -> np.ndarray:
    """New stance state ``[w, theta1, theta2, wd, theta1d, theta2d]`` relative to the new ankle.

    ``x_pre`` is the stance state just before heel strike, relative to the old ankle;
    ``new_ankle_offset = (dx, dy)`` is the new ankle minus the old one (m). ``hip_shift`` (m) is
    where the new stance leg's hip is relative to the old one's: (0, 0) for the one-hip model; with
    a pelvis (:mod:`klaw_ocp.kinematics.pelvis`) the landing leg's hip, ahead by its rotation. The
    hip's velocity and the upper body's angle and rate carry over unchanged either way. ``body``
    is not needed by this rule (it is purely kinematic) and is taken for symmetry with the other
    maps.
    """
    check_body(body)
    x = as_vector("x_pre", x_pre, 6)
    offset = as_vector("new_ankle_offset", new_ankle_offset, 2) - as_vector("hip_shift", hip_shift, 2)
    if x[0] <= 0:
        raise ConfigError(out_of_range("x_pre[0] (w)", x[0], "a positive leg length in m"))
    post, = evaluate(impact_functions()["heel_strike"], x, offset)
    if not post[0] > 0:
        # the hip coincides with the new ankle: theta1' is undefined
        raise ConfigError(out_of_range("new_ankle_offset", offset.tolist(), "a point other than the hip"))
    return post


def heel_strike_conserved(body, x, ankle, about=None) -> dict:
    """Momentum bookkeeping of a stance state, world frame, for checking the heel-strike map.

    ``x``: stance state relative to its ankle, which is at world position ``ankle``; ``about``:
    the point for angular momenta (default ``ankle``; pass the *new* ankle for the pre-impact
    state). Returns 2-arrays ``hip``, ``hip_velocity``, ``upper_body_momentum`` (m2 v_com2) and
    floats ``upper_body_spin`` (I2 theta2d), ``upper_body_angular_momentum`` (about ``about``),
    ``leg_angular_momentum`` and ``total_angular_momentum`` (stance leg, and leg + upper body,
    about ``about``). :data:`CONSERVED` lists the keys the map conserves, :data:`NOT_CONSERVED`
    those it does not.
    """
    body = check_body(body)
    x = as_vector("x", x, 6)
    ankle = as_vector("ankle", ankle, 2)
    about = ankle if about is None else as_vector("about", about, 2)
    w, th1, th2, wd, th1d, th2d = x
    e1, e1p = np.array([np.sin(th1), np.cos(th1)]), np.array([np.cos(th1), -np.sin(th1)])
    e2, e2p = np.array([np.sin(th2), np.cos(th2)]), np.array([np.cos(th2), -np.sin(th2)])
    hip, hip_vel = ankle + w * e1, wd * e1 + w * th1d * e1p
    com2, v2 = hip + body.r2 * e2, hip_vel + body.r2 * th2d * e2p
    com1, v1 = ankle + body.r1 * e1, body.r1 * th1d * e1p

    def cross_cw(r, v):
        return float(r[1] * v[0] - r[0] * v[1])

    h_upper = body.m2 * cross_cw(com2 - about, v2) + body.I2 * th2d
    h_leg = body.m1 * cross_cw(com1 - about, v1) + body.I1 * th1d
    return {"hip": hip, "hip_velocity": hip_vel, "upper_body_momentum": body.m2 * v2,
            "upper_body_spin": float(body.I2 * th2d), "upper_body_angular_momentum": h_upper,
            "leg_angular_momentum": h_leg, "total_angular_momentum": h_upper + h_leg}


def stance_lock_map(body, x, rule: str = choices.MOMENTUM) -> np.ndarray:
    """Stance state after the leg locks (wd = 0, section 4.2); ``rule`` in :data:`LOCK_RULES`."""
    body = check_body(body)
    x = as_vector("x", x, 6)
    if choice("rule", rule, LOCK_RULES) == choices.ZERO:
        return np.concatenate([x[:3], [0.0], x[4:]])
    return evaluate(impact_functions()["stance_lock"], x, body.dynamic_parameters())[0]


def knee_lock_map(body, x, hip_vel, rule: str = choices.MOMENTUM) -> np.ndarray:
    """Swing state ``[theta3, theta4, theta3d, theta4d]`` after the knee locks (theta4d = 0, eq. 5).

    ``hip_vel`` (m/s, world) is checked but does not change the result: the hip is prescribed, so
    its contribution to ``dT/dtheta3d`` is the same before and after (module docstring).
    """
    body = check_body(body)
    x = as_vector("x", x, 4)
    as_vector("hip_vel", hip_vel, 2)
    if choice("rule", rule, LOCK_RULES) == choices.ZERO:
        return np.concatenate([x[:3], [0.0]])
    return evaluate(impact_functions()["knee_lock"], x, body.dynamic_parameters())[0]
