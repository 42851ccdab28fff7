"""The torque and force shapes of section 4 (low-level control).

Each shape is a small function of time and state with a few free parameters; the subphase
problems choose those parameters so that the final conditions are met. Every function works with
floats and with CasADi SX alike, so the same expression serves the multiple-shooting and the
plain-shooting solvers.

- :func:`step_torque`: F_theta1 of the stance, a step input switched off at 0.4 t_step (§4.2).
- :func:`leg_force`: F_w, the spring-damper with position actuator pa (the lost eq. 4; ERRATA 8).
- :func:`spring_damper`: F_theta2 balancing the upper body (§4.2) and F_theta3 holding the thigh
  in swing2 (§4.3).
- :func:`decaying_exponential`: the paper's shape, ``magnitude * exp(-t / tau)``.
- :func:`decaying_exponential_about_mean`: F_theta3 in swing1 and F_theta4 in swing2 (§4.3), the
  decaying exponential with an asymptote, so that the subphase can meet a rate condition at its
  end beside the position (issue #36; docs/paper-map.md).
- :func:`hip_height_reference` and :func:`position_actuator`: the "monitoring" of pa (§4.2).
- :func:`piecewise_linear`: the pa profile that the tracking formulation frees over the grid.
"""
from __future__ import annotations

import casadi as ca
import numpy as np


def _if_else(cond, a, b):
    return ca.if_else(cond, a, b) if isinstance(cond, (ca.SX, ca.MX)) else (a if cond else b)


def step_torque(t, t_off, magnitude):
    """``magnitude`` for ``t < t_off``, zero afterwards (the paper's step input)."""
    return _if_else(t < t_off, magnitude, 0 * magnitude)


def decaying_exponential(t, t_start, time_constant, magnitude):
    """``magnitude * exp(-(t - t_start) / time_constant)``."""
    exp = ca.exp if isinstance(t, (ca.SX, ca.MX)) else np.exp
    return magnitude * exp(-(t - t_start) / time_constant)


def exponential_mean(duration, time_constant):
    """The mean of ``exp(-s / time_constant)`` over ``0 <= s <= duration``."""
    exp = ca.exp if isinstance(duration, (ca.SX, ca.MX)) else np.exp
    return time_constant / duration * (1 - exp(-duration / time_constant))


def decaying_exponential_about_mean(t, t_start, time_constant, exp_mean, fall, mean):
    """``mean + fall * (exp(-(t - t_start) / time_constant) - exp_mean)``: a decaying exponential
    whose time average over the subphase is ``mean`` and whose fall from start to end is about
    ``fall`` (``exp_mean`` = :func:`exponential_mean` of the subphase).

    The paper's shape has one free parameter, enough for the one position it imposes at the
    subphase's end; a limb that must also arrive at rest (the thigh at its peak at t1, the knee
    extending softly at t2) needs a second. The two are nearly decoupled: the mean sets the
    angular momentum the subphase ends with, the fall how early it is spent, so the plain
    shooting's one-unknown-at-a-time sweeps contract (pairing mean with the rate, fall with the
    position)."""
    return mean + fall * (decaying_exponential(t, t_start, time_constant, 1.0) - exp_mean)


def spring_damper(q, qd, stiffness, damping, q_rest, actuator=0.0):
    """``stiffness * (q_rest + actuator - q) - damping * qd``: a spring whose rest position the
    position actuator shifts."""
    return stiffness * (q_rest + actuator - q) - damping * qd


def leg_force(w, wd, stiffness, damping, l1, pa):
    """F_w = k_w (l1 + pa - w) - v_w wd: ERRATA 8's reading of the lost eq. 4 (pa shifts the rest length)."""
    return spring_damper(w, wd, stiffness, damping, l1, pa)


def piecewise_linear(s, knots):
    """The piecewise-linear function through ``knots`` at s = 0, 1/K, ..., 1 (K = len(knots) - 1),
    held at its end values outside [0, 1]: a sum of hat functions, smooth enough for Newton and
    IPOPT between the knots."""
    k = len(knots) - 1
    s = ca.fmin(ca.fmax(s, 0), 1) * k
    return sum(knot * ca.fmax(0, 1 - ca.fabs(s - i)) for i, knot in enumerate(knots))


def hip_height_reference(t, duration, y_start, y_end, excursion, rise=0.5, fall=0.5, power=1.0, settle=1.0):
    """The vertical sinusoid of the hip over one step (§4.2, after Inman) and its rate.

    Lowest at both heel strikes: ``y_start`` blends into ``y_end`` (the two heel-strike heights
    differ when the step length changes) and a bump of height ``excursion`` rises over the first
    ``rise`` of the step and falls over its last ``fall`` (fractions of ``duration``), each a half
    raised cosine, and holds its height between them; the fall's raised cosine runs in
    1 - (1 - r)^power of the fraction r of the fall still ahead, so that a power above 1 starts
    the fall gently and ends it steeply. The blend from ``y_start`` to ``y_end`` is complete at
    ``settle`` of the step (1: at its end, the paper's) and holds ``y_end`` after: a walk's closing
    step rises to standing height by t2 (``control.step``), so that its swing leg, coming down
    straight beside the stance leg, finds the hip high enough for a foot (issue #36 item 6). With ``rise = fall = 1/2`` and ``power`` 1 (the paper's
    reading) it is the raised cosine 0.5 (1 - cos 2 pi t / duration) that peaks at mid-step. Both end
    slopes are zero, so the hip's vertical velocity is continuous across the heel-strike map.

    People's hip stays high through terminal stance while the heel rises and keeps the leg long,
    and comes down in pre-swing (docs/human-gait.md): the attributes ``hip_rise_fraction``,
    ``hip_fall_fraction`` and ``hip_fall_power`` shape it so; the hip that falls no faster than the
    leg's reach allows keeps the stance knee on its schedule (kinematics/pitch_rules.py).
    """
    # numpy arrays (the table's rows) are evaluated with numpy: the same operations in the same
    # order, 40x faster than CasADi's DM one element-wise operation at a time
    m = np if isinstance(t, np.ndarray) else ca
    settled = settle * duration         # (the duration itself, to the bit, at settle 1)
    s = m.pi * m.fmin(t, settled) / settled
    blend = 0.5 * (1 - m.cos(s))
    up = m.pi * m.fmin(t / (rise * duration), 1)
    ahead = m.fmin((duration - t) / (fall * duration), 1)      # 1 where the fall begins, 0 at the end
    # (1 - ahead) kept off 0, where the power's derivative is infinite and the solvers' Jacobians
    # would multiply it by 0: NaN; 1e-30 ** power (power >= 1) changes nothing a solver can see
    since = m.fmax(1 - ahead, 1e-30)
    down = m.pi * (1 - since ** power)
    bump_up, bump_down = 0.5 * (1 - m.cos(up)), 0.5 * (1 - m.cos(down))
    y = y_start + (y_end - y_start) * blend + excursion * bump_up * bump_down
    down_rate = power * since ** (power - 1) / fall     # d(down / pi)/d(t / duration), while falling
    yd = ((y_end - y_start) * 0.5 * m.sin(s) * m.pi / settled
          + excursion * 0.5 * m.pi / duration * (m.sin(up) / rise * bump_down - bump_up * m.sin(down) * down_rate))
    return y, yd


def position_actuator(offset, gain, rate_gain, y_ref, yd_ref, y, yd):
    """pa monitored during stance (§4.2): raised when the hip drops below the sinusoid, lowered
    when it rises above; ``offset`` is the free parameter the stance problem solves for."""
    return offset + gain * (y_ref - y) + rate_gain * (yd_ref - yd)
