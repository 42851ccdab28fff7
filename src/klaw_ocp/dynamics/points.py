"""The models' points: forward kinematics of the dynamic models and the kinematic foot (sections
2.3, 3, 4.3; figures 2, 5-7): the foot's heel, metatarsal head and toe tip, the swing leg's
points, the stance hip, the upper body's centre of mass.

Serves ground-clearance constraints, plots and the animation. Positions are in the world frame
(x forward, y up, metres); the models' own conventions are those of :mod:`.stance` and
:mod:`.swing` (ERRATA "Conventions").

The foot (figures 5 and 6, Table B-1 rows 8-13), for a shank of absolute angle
``phi`` (``phi = theta3 + theta4`` for the swing leg), so that the ankle->knee unit vector is
``u = (sin phi, cos phi)``:

- ``u_b``: the backward sole direction, ``u`` rotated counter-clockwise by ``theta5``. theta5 is the
  angle between the leg axis and the foot's long axis, so 90 deg is a neutral ankle: a vertical
  shank then has a horizontal sole (ERRATA "Open choices", theta5). The angle knee-ankle-heel is
  then theta5 + omega8, the interior angle of eq. 3. theta5 > 90 deg lifts the toe (dorsiflexion),
  theta5 < 90 deg lowers it (plantar flexion).
- ``u_f = -u_b`` the forward sole direction, ``n`` = ``u_f`` rotated CCW by 90 deg (the foot's "up").
- ``heel = ankle + l8 u_b - l9 n`` (l8: heel to the ankle's projection on the sole, l9: ankle height).
- ``metatarsal = ankle + sqrt(l12^2 - l9^2) u_f - l9 n`` (l12 is the ankle to 1st metatarsal head
  *distance*, so its projection on the sole is the square root).
- ``toe = metatarsal + l13 * (u_f rotated CCW by theta6)``; theta6 is the toe dorsiflexion at the
  metatarsophalangeal joint (positive lifts the toe tip relative to the sole).

Check: vertical shank, theta5 = 90 deg, ankle (0, l9) -> heel (-l8, 0), sole and toe on y = 0.
"""
from __future__ import annotations

import math

import casadi as ca
import numpy as np

from ..casadi_builds import built_once
from ._checks import as_scalar, as_vector, check_body, to_numpy
from .evaluate import evaluate
from .stance import stance_functions
from .swing import swing_functions


def _rotate_ccw(v, angle):
    c, s = ca.cos(angle), ca.sin(angle)
    return ca.vertcat(c * v[0] - s * v[1], s * v[0] + c * v[1])


def foot_points_sx(ankle, shank_angle, theta5, theta6, l8, l9, l12, l13) -> dict:
    """Heel, metatarsal head and toe tip of the kinematic foot (see the module docstring).

    Works with CasADi SX/MX symbols and with plain floats (then the points are 2x1 DM).
    """
    ankle = ca.vertcat(ankle[0], ankle[1])
    u = ca.vertcat(ca.sin(shank_angle), ca.cos(shank_angle))
    u_b = _rotate_ccw(u, theta5)
    u_f = -u_b
    n = ca.vertcat(-u_f[1], u_f[0])  # u_f rotated CCW by 90 deg
    heel = ankle + l8 * u_b - l9 * n
    metatarsal = ankle + ca.sqrt(l12 ** 2 - l9 ** 2) * u_f - l9 * n
    toe = metatarsal + l13 * _rotate_ccw(u_f, theta6)
    return {"heel": heel, "metatarsal": metatarsal, "toe": toe}


def foot_points_float(ankle_x: float, ankle_y: float, shank_angle: float, theta5: float, theta6: float,
                      l8: float, l9: float, l12: float, l13: float) -> tuple:
    """:func:`foot_points_sx` in plain float arithmetic: ``((heel), (metatarsal), (toe))`` as
    (x, y) pairs. The double support's root searches evaluate it thousands of times a walk, where
    a CasADi call (tens of microseconds) would cost more than the walk's dynamics; a test holds
    the two forms equal."""
    ux, uy = math.sin(shank_angle), math.cos(shank_angle)
    c5, s5 = math.cos(theta5), math.sin(theta5)
    bx, by = c5 * ux - s5 * uy, s5 * ux + c5 * uy        # u_b: u rotated CCW by theta5
    fx, fy = -bx, -by                                    # u_f
    nx, ny = -fy, fx                                     # n: u_f rotated CCW by 90 deg
    heel = (ankle_x + l8 * bx - l9 * nx, ankle_y + l8 * by - l9 * ny)
    reach = math.sqrt(l12 ** 2 - l9 ** 2)
    mx, my = ankle_x + reach * fx - l9 * nx, ankle_y + reach * fy - l9 * ny
    c6, s6 = math.cos(theta6), math.sin(theta6)
    toe = (mx + l13 * (c6 * fx - s6 * fy), my + l13 * (s6 * fx + c6 * fy))
    return heel, (mx, my), toe


def foot_points_arrays(ankle: np.ndarray, shank_angle, theta5, theta6,
                       l8: float, l9: float, l12: float, l13: float) -> tuple:
    """:func:`foot_points_float` over n samples at once (the body's frames): ``ankle`` (n, 2) and
    the angles (n,) -> ``(heel, metatarsal, toe)``, each (n, 2). A test holds it equal to the
    float form, which the root searches keep for its speed on single values."""
    ux, uy = np.sin(shank_angle), np.cos(shank_angle)
    c5, s5 = np.cos(theta5), np.sin(theta5)
    back = np.column_stack([c5 * ux - s5 * uy, s5 * ux + c5 * uy])      # u_b: u rotated CCW by theta5
    forward = -back                                                      # u_f
    up = np.column_stack([-forward[:, 1], forward[:, 0]])                # n: u_f rotated CCW by 90 deg
    heel = ankle + l8 * back - l9 * up
    metatarsal = ankle + math.sqrt(l12 ** 2 - l9 ** 2) * forward - l9 * up
    c6, s6 = np.cos(theta6)[:, None], np.sin(theta6)[:, None]
    return heel, metatarsal, metatarsal + l13 * (c6 * forward + s6 * up)   # u_f rotated CCW by theta6


def foot_points(body, ankle, shank_angle, theta5, theta6=0.0) -> dict:
    """Numeric :func:`foot_points_sx` for a :class:`~klaw_ocp.body.Body`: ``{heel, metatarsal, toe}``."""
    body = check_body(body)
    ankle = as_vector("ankle", ankle, 2)
    angles = [as_scalar("shank_angle", shank_angle), as_scalar("theta5", theta5), as_scalar("theta6", theta6)]
    pts = foot_points_float(float(ankle[0]), float(ankle[1]), *map(float, angles),
                            body.l8, body.l9, body.l12, body.l13)
    return {k: np.array(v) for k, v in zip(("heel", "metatarsal", "toe"), pts)}


def swing_leg_points(body, q, hip, theta5=math.pi / 2, theta6=0.0) -> dict:
    """World positions of the swing leg: ``hip, knee, ankle, heel, metatarsal, toe`` (2-arrays).

    ``q = [theta3, theta4]`` (rad), ``hip`` the world hip position (m); ``theta5``/``theta6`` the
    kinematic foot angles (rad), neutral by default.
    """
    body = check_body(body)
    q = as_vector("q", q, 2)
    hip = as_vector("hip", hip, 2)
    knee, ankle = (to_numpy(v) for v in swing_functions()["points"](q, hip, body.dynamic_parameters()))
    out = {"hip": hip, "knee": knee, "ankle": ankle}
    out.update(foot_points(body, ankle, q[0] + q[1], theta5, theta6))
    return out


def stance_hip(body, x_stance, ankle):
    """World hip position and velocity ``(pos, vel)`` of the stance state
    ``x = [w, theta1, theta2, wd, theta1d, theta2d]`` whose ankle is at world ``ankle``.
    """
    check_body(body)
    x = as_vector("x_stance", x_stance, 6)
    ankle = as_vector("ankle", ankle, 2)
    pos, vel, _ = evaluate(stance_functions()["hip"], x[:3], x[3:], np.zeros(3))
    return ankle + pos, vel


def stance_hips(body, states, ankle) -> tuple[np.ndarray, np.ndarray]:
    """:func:`stance_hip` of many stance states ``(n, >=6)`` in one call: world hip positions and
    velocities, each ``(n, 2)``."""
    check_body(body)
    states = np.atleast_2d(np.asarray(states, float))[:, :6]
    n = len(states)   # (n, 3) blocks in C order are CasADi's (3, n) columns
    pos, vel, _ = evaluate(_hip_map(n), states[:, :3], states[:, 3:], np.zeros(3))
    return np.asarray(ankle, float) + pos.reshape(n, 2), vel.reshape(n, 2)


@built_once
def _hip_map(n: int):
    return stance_functions()["hip"].map(n)


def upper_body_com(body, q_stance, ankle):
    """World position ``(x, y)`` of the upper-body (head-arms-trunk) centre of mass."""
    body = check_body(body)
    q = as_vector("q_stance", q_stance, 3)
    ankle = as_vector("ankle", ankle, 2)
    _, _, trunk = stance_functions()["points"](q, body.dynamic_parameters())
    x, y = ankle + to_numpy(trunk)
    return float(x), float(y)
