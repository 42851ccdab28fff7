"""The body's swing legs, compiled (:mod:`klaw_ocp.kernels`): everything of
:func:`.swing_legs.swing_legs` that is a formula of one sample, on either side of the ground
guard's smooth turns (:mod:`.swing_foot_guard`, whose envelopes run along each step's grid and
stay numpy).

- :func:`leg_function` (the leg at a sample of a step's swing, before the guard): the dynamics'
  θ3, θ4 on the swing's Hermite curves hung from the planar model's swing hip (the model's leg,
  :func:`klaw_ocp.kinematics.leg_geometry.leg_fk`); the body's leg, which keeps the model's
  hip-ankle distance from its own hip and blends into the virtual legs at toe-off and heel strike
  (:mod:`.swing_legs`' docstring); the foot's schedule, the timed one (the ends' foot) and the one
  that relaxes with the body's knee (:func:`klaw_ocp.kinematics.swing_foot.schedule_angles`,
  the same function on symbols); and the ground's window of the foot's angle with the turn it
  requires (:func:`.swing_foot_guard._ground_window`).
- :func:`foot_function` (a frame, after the guard): the foot's angles with the guard's turn, its
  points carried up with the lifted ankle (:func:`klaw_ocp.dynamics.points.foot_points_sx`) and
  the knee the body's hip and that ankle give (:func:`.kernel_forms.leg_ik`).

As numpy these were some 300 small array operations a step of the playground (0.9 ms on
2026-12-07's machine: docs/performance.md); tests/test_swing_kernel.py holds them to the numpy
forms, which the walk's summary (the swing foot's clearance) and the one-step guard keep.
"""
from __future__ import annotations

import math
import sys
from functools import lru_cache

import casadi as ca
import numpy as np

from ..casadi_builds import built_once
from ..dynamics import points
from ..dynamics.points import foot_points_sx
from ..kernels import source_key
from ..kinematics import swing_foot
from ..kinematics.swing_foot import SCHEDULE_FIELDS, schedule_angles
from . import walk_samples
from .kernel_forms import clamp, evaluate, knee_flexion_for_reach, leg_ik, mapped_library, round_half_even, smoothstep
from .walk_samples import hermite_sum

#: the fraction of swing1 over which the body's swing leg blends from the virtual leg's toe-off
#: posture (the model's ankle reached from the leg's own hip) into the dynamic knee angle
TOE_OFF_BLEND = 0.5
#: a row of :func:`leg_function`: its step coordinate u on the swing's curves and the nodes that
#: start and end its interval (u, θ3, θ4, their rates per unit u), the model's swing hip and the
#: leg's own hip (x, height in its plane), the step-local time, the step's foot schedule, and the
#: step's offsets of the ankle and of the foot's turn at toe-off and at heel strike
NODE = ("u", "theta3", "theta4", "rate3", "rate4")
LEG_COLUMNS = (("u",) + tuple(f"{n}_0" for n in NODE) + tuple(f"{n}_1" for n in NODE)
               + ("model_hip_x", "model_hip_y", "own_x", "own_y", "tau") + SCHEDULE_FIELDS
               + ("toe_off_dx", "toe_off_dy", "toe_off_turn", "landing_dx", "landing_dy", "landing_turn"))
#: a row of :func:`foot_function`: the step-local time, the schedule, the body's knee there (the
#: guard grid's, interpolated), the guard's turn and the ankle's lift, the body's shank angle,
#: ankle and own hip
FOOT_COLUMNS = ("tau",) + SCHEDULE_FIELDS + ("knee", "turn", "lift", "shank", "ankle_x", "ankle_y", "own_x", "own_y")
#: the body's lengths, and the heel's distance from the ankle and its angle (np.hypot(l8, l9),
#: math.atan2(l9, l8): swing_foot_guard._ground_window's)
CONSTANTS = ("l3", "l4", "l8", "l9", "l12", "l13", "metatarsal_reach", "heel_radius", "heel_phase")
LEG_OUTPUTS = {"model_shank": 1, "model_ankle": 2, "timed_theta5": 1, "shank": 1, "ankle": 2, "knee": 1,
               "theta5": 1, "theta6": 1, "lowest": 1, "highest": 1, "fits": 1, "level": 1, "required": 1}
FOOT_OUTPUTS = {"theta5": 1, "theta6": 1, "ankle": 2, "heel": 2, "metatarsal": 2, "toe": 2, "knee": 2}
#: samples per call: a step's guard grid and frames (about 250), its ends (a few), its frames
LEG_BLOCK, ENDS_BLOCK, FOOT_BLOCK = 128, 8, 32


def ground_window(c, theta6, ankle_y, shank) -> tuple:
    """swing_foot_guard._ground_window of one sample: (lowest, highest θ5, whether one fits, θ5
    of the level sole)."""
    reach, l9, l13 = c["metatarsal_reach"], c["l9"], c["l13"]
    toe_a, toe_b = -(reach + l13 * ca.cos(theta6)), l9 - l13 * ca.sin(theta6)
    lower, upper, fits = -ca.inf, ca.inf, 1
    # the heel's circle about the ankle is the body's (a constant); the toe tip's turns with θ6
    for radius, phase in ((c["heel_radius"], c["heel_phase"]), (ca.hypot(toe_a, toe_b), ca.atan2(toe_b, toe_a))):
        centre = math.pi / 2 - phase
        centre = centre + 2 * math.pi * round_half_even((math.pi - centre) / (2 * math.pi))
        half = ca.acos(clamp(-ankle_y / radius, -1.0, 1.0))
        fits = ca.logic_and(fits, ca.fabs(math.pi - centre) <= half)
        free = ankle_y >= radius
        lower = ca.if_else(free, lower, ca.fmax(lower, centre - half))
        upper = ca.if_else(free, upper, ca.fmin(upper, centre + half))
    to_theta5 = shank - math.pi / 2
    return lower + to_theta5, upper + to_theta5, fits, math.pi + to_theta5


def _symbols(columns, constants=CONSTANTS):
    row, shared = ca.SX.sym("row", len(columns)), ca.SX.sym("constants", len(constants))
    return row, shared, {n: row[i] for i, n in enumerate(columns)}, {n: shared[i] for i, n in enumerate(constants)}


def leg_function() -> ca.Function:
    """One sample of a swing: (its row (LEG_COLUMNS), the constants) -> LEG_OUTPUTS."""
    row, shared, x, c = _symbols(LEG_COLUMNS)
    l3, l4 = c["l3"], c["l4"]
    start = x["u_0"]
    h = x["u_1"] - start
    s = (x["u"] - start) / h
    theta3, theta4 = (hermite_sum(s, h, x[f"{v}_0"], x[f"rate{k}_0"], x[f"{v}_1"], x[f"rate{k}_1"])
                      for v, k in (("theta3", 3), ("theta4", 4)))
    # the model's leg from its swing hip (leg_fk)
    model_shank = theta3 + theta4
    knee_x, knee_y = x["model_hip_x"] - l3 * ca.sin(theta3), x["model_hip_y"] - l3 * ca.cos(theta3)
    ankle_x, ankle_y = knee_x - l4 * ca.sin(model_shank), knee_y - l4 * ca.cos(model_shank)
    schedule = {name: x[name] for name in SCHEDULE_FIELDS}
    tau = x["tau"]
    timed_theta5 = schedule_angles(tau, schedule, clamp)[0]
    # the body's leg (swing_legs.body_leg): the model's hip-ankle distance from its own hip, blended
    # into the virtual legs' posture at toe-off and at heel strike
    dynamic = ca.hypot(ankle_x - x["model_hip_x"], ankle_y - x["model_hip_y"])
    t_to, t1, t2, t_hs = (x[name] for name in ("t_toe_off", "t1", "t2", "t_heel_strike"))
    leaves = 1 - smoothstep((tau - t_to) / (TOE_OFF_BLEND * (t1 - t_to)))
    lands = smoothstep((tau - t2) / ca.fmax(t_hs - t2, 1e-12))
    towards_x = ankle_x + leaves * x["toe_off_dx"] + lands * x["landing_dx"] - x["own_x"]
    towards_y = ankle_y + leaves * x["toe_off_dy"] + lands * x["landing_dy"] - x["own_y"]
    reached = ca.hypot(towards_x, towards_y)
    distance = dynamic + ca.fmax(leaves, lands * lands) * (reached - dynamic)
    shank = model_shank + (leaves * x["toe_off_turn"] + lands * x["landing_turn"])
    scale = distance / ca.fmax(reached, 1e-12)
    body_x, body_y = x["own_x"] + towards_x * scale, x["own_y"] + towards_y * scale
    # the foot's schedule with the body's knee, and the ground's window of θ5 (the guard's start)
    knee = knee_flexion_for_reach(l3, l4, ca.hypot(body_x - x["own_x"], body_y - x["own_y"]))
    theta5, theta6 = schedule_angles(tau, schedule, clamp, knee)
    lowest, highest, fits, level = ground_window(c, theta6, body_y, shank)
    required = ca.if_else(fits, clamp(theta5, lowest, highest), level) - theta5
    out = {"model_shank": model_shank, "model_ankle": ca.vertcat(ankle_x, ankle_y), "timed_theta5": timed_theta5,
           "shank": shank, "ankle": ca.vertcat(body_x, body_y), "knee": knee, "theta5": theta5, "theta6": theta6,
           "lowest": lowest, "highest": highest, "fits": fits, "level": level, "required": required}
    return ca.Function("body_swing_leg", [row, shared], [out[n] for n in LEG_OUTPUTS], ["row", "constants"], list(LEG_OUTPUTS))


def foot_function() -> ca.Function:
    """One frame of a swing, after the guard: (its row (FOOT_COLUMNS), the constants) -> FOOT_OUTPUTS."""
    row, shared, x, c = _symbols(FOOT_COLUMNS)
    theta5, theta6 = schedule_angles(x["tau"], {name: x[name] for name in SCHEDULE_FIELDS}, clamp, x["knee"])
    theta5 = theta5 + x["turn"]
    ankle = (x["ankle_x"], x["ankle_y"])
    points = foot_points_sx(ankle, x["shank"], theta5, theta6, c["l8"], c["l9"], c["l12"], c["l13"])
    lift = x["lift"]
    up = lambda p: ca.vertcat(p[0] + 0.0, p[1] + lift)     # noqa: E731 - carried up with the ankle
    lifted = up(ankle)
    _, _, knee_x, knee_y, _ = leg_ik(c["l3"], c["l4"], x["own_x"], x["own_y"], lifted[0], lifted[1])
    out = {"theta5": theta5, "theta6": theta6, "ankle": lifted, "heel": up(points["heel"]),
           "metatarsal": up(points["metatarsal"]), "toe": up(points["toe"]), "knee": ca.vertcat(knee_x, knee_y)}
    return ca.Function("body_swing_foot", [row, shared], [out[n] for n in FOOT_OUTPUTS], ["row", "constants"], list(FOOT_OUTPUTS))


@built_once
def libraries() -> tuple:
    """The kernels' libraries, the legs' and the feet's (built once; :meth:`~klaw_ocp.kernels.KernelLibrary.load`
    compiles them)."""
    # the key: the source of every module whose code builds the expressions
    key = [source_key(sys.modules[__name__], swing_foot, points, walk_samples), LEG_COLUMNS, FOOT_COLUMNS, CONSTANTS]
    return (mapped_library(key, leg_function, {"body_swing_legs": LEG_BLOCK, "body_swing_ends": ENDS_BLOCK}),
            mapped_library(key, foot_function, {"body_swing_feet": FOOT_BLOCK}))


@lru_cache(maxsize=None)
def _kernels() -> dict:
    return {name: fn for library in libraries() for name, fn in library.functions().items()}


@lru_cache(maxsize=16)
def constants(body) -> tuple:
    """:data:`CONSTANTS` of a body (one per body, shared)."""
    return (body.l3, body.l4, body.l8, body.l9, body.l12, body.l13, body.metatarsal_reach,
            float(np.hypot(body.l8, body.l9)), math.atan2(body.l9, body.l8))


def legs_at(rows, shared, ends: bool = False) -> dict:
    """:func:`leg_function` over n rows (n, len(LEG_COLUMNS)) -> LEG_OUTPUTS name -> (n,) or (n, 2);
    ``ends``: a few rows (each step's toe-off and heel strike), in the smaller block."""
    kernel = _kernels()["body_swing_ends" if ends else "body_swing_legs"]
    return evaluate(kernel, ENDS_BLOCK if ends else LEG_BLOCK, rows, shared, LEG_OUTPUTS)


def feet_at(rows, shared) -> dict:
    """:func:`foot_function` over n frames (n, len(FOOT_COLUMNS)) -> FOOT_OUTPUTS name -> (n,) or (n, 2)."""
    return evaluate(_kernels()["body_swing_feet"], FOOT_BLOCK, rows, shared, FOOT_OUTPUTS)
