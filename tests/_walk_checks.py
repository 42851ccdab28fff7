"""Support for the walk-level checks (tests/test_walk_checks.py): walks whose subphase problems are
recorded, so that a test can re-simulate them with an integrator of its own instead of trusting
what the solvers report about themselves.

Nothing here calls a solver's integrator or kernels: trajectories between the stored samples are
re-integrated with SciPy's DOP853 on the subphase's own right-hand side (the model the walk is
defined by), and every geometric quantity is recomputed from the states with the forward
kinematics of :mod:`klaw_ocp.dynamics`.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np
from scipy.integrate import solve_ivp

from klaw_ocp.body_motion.swing_foot_guard import grounded_angles, guard_grid, lifted_foot
from klaw_ocp.config import ExperimentConfig
from klaw_ocp.control.stance_law import STANCE_CONTEXT
from klaw_ocp.control.step import StepController
from klaw_ocp.control.swing_law import SWING_CONTEXT
from klaw_ocp.dynamics import foot_points_float
from klaw_ocp.kinematics.swing_foot import SCHEDULE_FIELDS, SwingFoot
from klaw_ocp.solvers.problem import mapped
from klaw_ocp.walk import simulate_walk, walk_spec

METHODS = ("multiple-shooting", "plain-shooting")

#: The envelope's coarse grid (docs/envelope.md): speed (km/h), height (m), mass (kg), start from
#: rest, end at rest. Every corner of the body range, both ends of the speed range, and each
#: combination of start and stop.
COARSE = [
    (0.5, 1.8, 80, True, True), (1.0, 1.5, 50, False, False), (2.0, 2.0, 120, True, False),
    (3.0, 1.4, 40, True, True), (4.0, 2.1, 150, True, True), (5.0, 1.8, 80, False, True),
    (6.5, 1.5, 60, True, False), (8.0, 2.0, 90, False, False), (9.0, 1.8, 80, True, True),
]
COARSE_IDS = [f"{v}kmh-{h}m-{m}kg{'-rest' if r else ''}{'-stop' if s else ''}" for v, h, m, r, s in COARSE]

#: the swing2 toe clearance is a constraint at the grid's nodes; between them the toe may dip
#: below it by a fraction of a millimetre (0.33 mm is the deepest on the coarse grid, in first steps
#: from rest and closing steps, since the ankle relaxes to neutral over the second half of swing2,
#: issue #34; 0.07 mm with the ankle held dorsiflexed)
TOE_DIP_BETWEEN_NODES = 5e-4

_LOCKED = STANCE_CONTEXT.index["locked"]


@dataclass
class RecordedWalk:
    walk: object
    #: (step index, subphase name) -> (SubphaseProblem, SubphaseSolution) of the solve the walk kept
    problems: dict
    #: (method, grid point) of a :func:`coarse_walk`
    key: tuple = ()

    def dense(self, step: int, subphase: str) -> "Dense":
        """The dense re-integration of one subphase (cached for the coarse grid's walks)."""
        if self.key:
            return coarse_dense(*self.key, step, subphase)
        return dense_trajectory(*self.problems[(step, subphase)])

    @property
    def body(self):
        return self.walk.spec.body


def grid_config(speed, height, mass, rest, stop, steps=2) -> dict:
    return {"name": "checks", "body": {"height": height, "mass": mass},
            "walk": {"speed": speed, "steps": steps, "start_from_rest": rest, "end_at_rest": stop}}


def record_walk(mapping: dict, method: str) -> RecordedWalk:
    """Simulate a walk and keep every subphase problem with the solution the walk used (the last
    solve of each subphase of each step: the periodic start's trial stances come before it)."""
    problems = {}
    original = StepController._solve

    def spy(self, step, problem, remember=True):
        solution = original(self, step, problem, remember)
        problems[(step, solution.name)] = (problem, solution)     # (a closing step's swing2 too)
        return solution
    StepController._solve = spy
    try:
        walk = simulate_walk(walk_spec(ExperimentConfig.from_mapping(mapping), method))
    finally:
        StepController._solve = original
    return RecordedWalk(walk, problems)


@lru_cache(maxsize=None)
def coarse_walk(method: str, point: tuple) -> RecordedWalk:
    """One walk of the coarse grid, simulated once per test session."""
    recorded = record_walk(grid_config(*point), method)
    recorded.key = (method, point)
    return recorded


@dataclass
class Dense:
    t: np.ndarray            # samples between the stored ones (the stored ones included)
    x: np.ndarray            # (len(t), nx) states there
    gaps: list               # (stored sample k, max |x_k+1 - integrated x_k+1|) for each interval


def _locked_after(events, t, locked: bool = False) -> bool:
    """Whether the stance leg is locked at ``t`` (plain shooting's lock events, section 4.2), from
    ``locked`` at the subphase's start (a swing's stance may start locked: the stance's state)."""
    for name, t_event in sorted(events, key=lambda e: e[1]):
        if t_event <= t + 1e-12:
            locked = name == "leg_too_long"
    return locked


def dense_trajectory(problem, solution, per_interval: int = 8, rtol: float = 1e-10) -> Dense:
    """Re-integrate every interval between stored samples from its stored start, on ``per_interval``
    sub-samples, with the subphase's right-hand side and solved parameters. All intervals are one
    ODE system in the normalised time s of each interval (t = t_k + s·h_k), so one mapped call of
    the right-hand side serves them all. A lock event of plain shooting switches the stance model
    to its rigid leg, as the event does in the solver; the interval that ends on an event is not
    compared (its stored end is after the lock map)."""
    spec = problem.spec
    u = np.array([solution.parameters[k] for k in spec.unknown_names])
    t = np.asarray(solution.t, float)
    n, nx = len(t) - 1, spec.nx
    starts, h = t[:-1], np.diff(t)
    contexts = np.repeat(problem.context[:, None], n, axis=1)
    initially = bool(problem.context[_LOCKED])
    contexts[_LOCKED, :] = [float(_locked_after(solution.events, t0, initially)) for t0 in starts]
    rhs_all = mapped(spec.rhs, n)

    def rhs(s, flat):
        xs = flat.reshape(n, nx).T
        return (np.asarray(rhs_all(xs, starts + s * h, u, contexts)) * h).T.ravel()
    samples = np.linspace(0.0, 1.0, per_interval + 1)
    run = solve_ivp(rhs, (0.0, 1.0), np.asarray(solution.states[:-1], float).ravel(), method="DOP853",
                    rtol=rtol, atol=rtol * 1e-2, t_eval=samples)
    ends = run.y[:, -1].reshape(n, nx)
    event_times = [t_event for _, t_event in solution.events]
    gaps = [(k, float(np.max(np.abs(ends[k] - solution.states[k + 1])))) for k in range(n)
            if not any(abs(t[k + 1] - t_event) < 1e-12 for t_event in event_times)]
    inner = run.y[:, :-1].reshape(n, nx, per_interval)            # (interval, state, sample)
    dense_t = (starts[:, None] + samples[None, :-1] * h[:, None]).ravel()
    dense_x = inner.transpose(0, 2, 1).reshape(n * per_interval, nx)
    return Dense(np.append(dense_t, t[-1]), np.vstack([dense_x, solution.states[-1:]]), gaps)


@lru_cache(maxsize=None)
def coarse_dense(method: str, point: tuple, step: int, subphase: str) -> Dense:
    """:func:`dense_trajectory` of one subphase of a :func:`coarse_walk`, computed once."""
    problem, solution = coarse_walk(method, point).problems[(step, subphase)]
    return dense_trajectory(problem, solution)


def world_hips(body, states: np.ndarray, origin_x: float) -> np.ndarray:
    """World hip positions of stance states (n, >=6): the stance ankle at (origin_x, l9) plus
    w·(sin θ1, cos θ1) (ERRATA "Conventions"), written out here rather than taken from the package."""
    w, theta1 = states[:, 0], states[:, 1]
    return np.column_stack([origin_x + w * np.sin(theta1), body.l9 + w * np.cos(theta1)])


def world_hip_velocities(states: np.ndarray) -> np.ndarray:
    w, theta1, wd, theta1d = states[:, 0], states[:, 1], states[:, 3], states[:, 4]
    return np.column_stack([wd * np.sin(theta1) + w * theta1d * np.cos(theta1),
                            wd * np.cos(theta1) - w * theta1d * np.sin(theta1)])


def swing_foot_schedule(context: np.ndarray) -> SwingFoot:
    """The swing foot's schedule the swing's context carries (kinematics/swing_foot.py, the
    formula the swing's path functions use)."""
    return SwingFoot(**{name: float(context[SWING_CONTEXT.index[f"foot_{name}"]]) for name in SCHEDULE_FIELDS})


def swing_ankle_heights(body, origin_x: float, name: str, dense: Dense, pelvis=None) -> np.ndarray:
    """Height above the ground (m) of the swing ankle at the dense samples of a swing subphase;
    given the step's ``pelvis``, of the leg hanging from the pelvis's other hip as it was solved
    (kinematics/pelvis.py), else from the stance hip."""
    hips = world_hips(body, dense.x, origin_x)
    if pelvis is not None:
        hips = pelvis.swing_side_hips(dense.t, hips)
    theta3 = dense.x[:, 6]
    theta4 = dense.x[:, 7] if name != "swing3" else np.zeros(len(dense.t))
    return hips[:, 1] - body.l3 * np.cos(theta3) - body.l4 * np.cos(theta3 + theta4)


def swing_foot_heights(body, origin_x: float, name: str, context, dense: Dense,
                       swing_leg=None) -> tuple[np.ndarray, np.ndarray]:
    """Heights above the ground (m) of the swing foot's toe tip and heel at the dense samples of a
    swing subphase: the hip from the carried stance state, the leg from θ3 and θ4 (0 in swing3,
    where the knee is locked) with the thigh l3 and shank l4, the foot from
    :func:`klaw_ocp.dynamics.foot_points_float`. The foot is the scheduled one the solvers' path
    functions see, or, given ``swing_leg`` (the whole swing's leg: :func:`swing_leg_function`),
    the body's foot, turned where the schedule would put it into the ground."""
    hips = world_hips(body, dense.x, origin_x)
    theta3 = dense.x[:, 6]
    theta4 = dense.x[:, 7] if name != "swing3" else np.zeros(len(dense.t))
    knee = hips - body.l3 * np.column_stack([np.sin(theta3), np.cos(theta3)])
    ankle = knee - body.l4 * np.column_stack([np.sin(theta3 + theta4), np.cos(theta3 + theta4)])
    schedule = swing_foot_schedule(context)
    theta5, theta6 = (schedule.angles(dense.t) if swing_leg is None
                      else grounded_angles(body, schedule, dense.t, swing_leg))
    toe, heel = np.empty(len(dense.t)), np.empty(len(dense.t))
    for i in range(len(dense.t)):
        foot_heel, _, foot_toe = foot_points_float(ankle[i, 0], ankle[i, 1], theta3[i] + theta4[i], theta5[i],
                                                   theta6[i], body.l8, body.l9, body.l12, body.l13)
        toe[i], heel[i] = foot_toe[1], foot_heel[1]
    return toe, heel


def swing_body_lift(recorded: RecordedWalk, step):
    """times -> how far the body lifts the swing ankle above the dynamic leg's
    (body_motion.swing_foot_guard.lifted_foot), from the dense samples of swing1, swing2 and swing3."""
    body, t, hip, ankle, shank = recorded.body, [], [], [], []
    for name in ("swing1", "swing2", "swing3"):
        dense = recorded.dense(step.index, name)
        hips = world_hips(body, dense.x, step.origin_x)
        theta3 = dense.x[:, 6]
        theta4 = dense.x[:, 7] if name != "swing3" else np.zeros(len(dense.t))
        t.append(dense.t)
        hip.append(hips)
        ankle.append(hips - body.l3 * np.column_stack([np.sin(theta3), np.cos(theta3)])
                     - body.l4 * np.column_stack([np.sin(theta3 + theta4), np.cos(theta3 + theta4)]))
        shank.append(theta3 + theta4)
    t, hip, ankle, shank = np.concatenate(t), np.vstack(hip), np.vstack(ankle), np.concatenate(shank)
    grid = guard_grid(step.swing_foot)
    on_grid = lambda v: np.column_stack([np.interp(grid, t, c) for c in np.atleast_2d(v.T)])
    _, _, lift = lifted_foot(body, step.swing_foot, grid, grid, on_grid(hip), on_grid(ankle), on_grid(shank)[:, 0])
    return lambda times: np.interp(times, grid, lift)


def swing_leg_function(recorded: RecordedWalk, step):
    """times -> (ankle height, shank angle, knee flexion) of a step's swing leg, linear between the
    dense samples of swing1, swing2 and swing3 (what the body's foot needs:
    body_motion.swing_foot_guard.grounded_angles)."""
    t, ankle_y, shank, knee = [], [], [], []
    for name in ("swing1", "swing2", "swing3"):
        dense = recorded.dense(step.index, name)
        t.append(dense.t)
        ankle_y.append(swing_ankle_heights(recorded.body, step.origin_x, name, dense))
        knee.append(dense.x[:, 7] if name != "swing3" else np.zeros(len(dense.t)))
        shank.append(dense.x[:, 6] + knee[-1])
    t, ankle_y, shank, knee = (np.concatenate(v) for v in (t, ankle_y, shank, knee))
    return lambda times: (np.interp(times, t, ankle_y), np.interp(times, t, shank), np.interp(times, t, knee))


def eq2_timings(step_frequency_spm: float, swing1_fraction=0.5, swing2_fraction=0.85) -> dict:
    """Eq. 2 and section 4.3's split, computed here from the step frequency alone (s)."""
    t_cycle = 120.0 / step_frequency_spm
    t_step = t_cycle / 2
    t_ds = (-0.16 * step_frequency_spm + 29.08) * t_cycle / 100
    t_swing = t_step - t_ds
    return {"t_step": t_step, "t_ds": t_ds, "t1": t_ds + swing1_fraction * t_swing,
            "t2": t_ds + swing2_fraction * t_swing}


def eq3_landing(body, step_length: float, theta5_impact_deg: float, pelvic_rotation_deg: float = 0.0,
                hip_lead: float = 0.0) -> dict:
    """Eq. 3's heel-strike posture, computed here from the body and the step alone: the landing
    heel (relative to the stance ankle's x), the stance hip (relative to the stance ankle) and the
    landing leg's hip, the pelvis's other one, l0 sin(rotation) ahead of it at the same height
    (each leg spans half of the step less that), the stance hip ``hip_lead`` of the step ahead of
    half-way (the attribute heel_strike_hip_lead; 0 in the paper)."""
    l1, l8, l9, l11 = body.l1, body.l8, body.l9, body.l11
    omega8 = math.acos(l8 / l11)
    r = math.sqrt(l1 ** 2 + l11 ** 2 - 2 * l1 * l11 * math.cos(math.radians(theta5_impact_deg) + omega8))
    shift = body.l0 * math.sin(math.radians(pelvic_rotation_deg)) if step_length > 0 else 0.0
    heel_x = step_length - l8
    hip_x = (step_length - shift) / 2 + (hip_lead * step_length if step_length > 0 else 0.0)
    hip_y = math.sqrt(r ** 2 - (heel_x - hip_x - shift) ** 2)
    return {"heel_x": heel_x, "hip": np.array([hip_x, hip_y - l9]), "landing_hip": np.array([hip_x + shift, hip_y - l9])}
