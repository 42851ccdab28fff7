"""The torque and force shapes of section 4 (low-level control).

Each shape is a small function of time and state with a few free parameters; the subphase
problems choose those parameters so that the final conditions are met. Every function works with
floats and with CasADi SX alike, so the same expression serves the multiple-shooting and the
plain-shooting solvers.

- :func:`step_torque`: F_theta1 of the stance, a step input switched off at 0.4 t_step (§4.2).
- :func:`leg_force`: F_w, the spring-damper with position actuator pa (the lost eq. 4; ERRATA 8).
- :func:`spring_damper`: F_theta2 balancing the upper body (§4.2) and F_theta3 holding the thigh
  in swing2 (§4.3).
- :func:`decaying_exponential`: F_theta3 in swing1 and F_theta4 in swing2 (§4.3).
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


def hip_height_reference(t, duration, y_start, y_end, excursion):
    """The vertical sinusoid of the hip over one step (§4.2, after Inman) and its rate.

    Lowest at both heel strikes, highest at mid-step: ``y_start`` blends into ``y_end`` (the two
    heel-strike heights differ when the step length changes) and a raised-cosine bump of height
    ``excursion`` peaks at ``duration / 2``. Both end slopes are zero, so the hip's vertical
    velocity is continuous across the heel-strike map.
    """
    s = ca.pi * t / duration
    blend = 0.5 * (1 - ca.cos(s))
    bump = 0.5 * (1 - ca.cos(2 * s))
    y = y_start + (y_end - y_start) * blend + excursion * bump
    yd = ((y_end - y_start) * 0.5 * ca.sin(s) + excursion * ca.sin(2 * s)) * ca.pi / duration
    return y, yd


def position_actuator(offset, gain, rate_gain, y_ref, yd_ref, y, yd):
    """pa monitored during stance (§4.2): raised when the hip drops below the sinusoid, lowered
    when it rises above; ``offset`` is the free parameter the stance problem solves for."""
    return offset + gain * (y_ref - y) + rate_gain * (yd_ref - yd)
