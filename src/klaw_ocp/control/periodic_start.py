"""The periodic orbit of a step (§5: a walk that starts "walking"), for the middle level's first step.

A walk that does not start from rest begins where its first step would hand its stance on to
itself: the stance state at heel strike that the step's stance and its heel-strike map (onto the
landing leg's own hip, the pelvis's other one) carry back to itself. :func:`periodic_start` finds
it in two stages: the hip speed whose hip leaves the step as fast as it entered it (secant method
from the landing posture of eq. 3, a start near enough to the orbit for every stance to have a solution),
then the whole state by passes through the step with Anderson's mixing. The stance does not depend
on the swing (assumption 4), so the orbit of the stance is the walk's.
"""
from __future__ import annotations

import math

import numpy as np

from ..dynamics import heel_strike_map, stance_hip
from ..errors import ConvergenceError
from .step import StepController, StepInput


def _walking_state(con, speed: float, theta2: float) -> np.ndarray:
    """Heel-strike stance state (the landing leg's posture of eq. 3) with a horizontal hip velocity
    ``speed``."""
    w, th = con.landing_w, con.landing_theta1
    return np.array([w, th, theta2, speed * math.sin(th), speed * math.cos(th) / w, 0.0])


#: the periodic orbit's tolerance on the stance state at heel strike (m, rad, m/s, rad/s)
PERIODIC_TOL = 1e-10
#: at most this many passes through the step map (with Anderson's mixing it meets the orbit in
#: four to six)
PERIODIC_PASSES = 20
#: how many earlier passes Anderson's mixing combines (:func:`_anderson`)
PERIODIC_DEPTH = 3


def periodic_start(controller: StepController, plan, inp: StepInput, tol: float = 1e-9) -> np.ndarray:
    """The stance state at heel strike on the periodic orbit of the step ``plan``.

    First the hip speed whose hip leaves the step as fast as it entered it (secant method, from
    the landing posture of eq. 3 with the trunk at its reference and at rest): a start close enough to the
    orbit for every stance to have a solution. Then the whole state is carried through the step's
    stance and its heel-strike map (onto the landing leg's own hip, the pelvis's other one) until
    it repeats: theta2 and the trunk's rate, which the balance controller settles, and the hip's
    vertical velocity, which the secant leaves free (:data:`PERIODIC_TOL`). The stance does not
    depend on the swing (assumption 4), so the orbit of the stance is the walk's."""
    x, stance = _speed_matched_start(controller, plan, inp, tol)   # its stance solved already
    solved = x
    con, body = plan.constraints, controller.body
    xs, gs = [], []   # the states tried and where the step took them (Anderson's history)
    for _ in range(PERIODIC_PASSES):
        if stance is None:
            inp.x0 = x
            try:
                stance = controller.solve_stance(plan, inp, 0)
            except ConvergenceError:
                break   # start from the last state whose stance was solved, near the orbit
        solved = x
        g = heel_strike_map(body, stance.final_state, np.array([con.step_length, 0.0]),
                            hip_shift=np.array([con.hip_shift, 0.0]))
        if np.max(np.abs(g - x)) <= PERIODIC_TOL:
            break
        xs, gs = (xs + [x])[-PERIODIC_DEPTH - 1:], (gs + [g])[-PERIODIC_DEPTH - 1:]
        x, stance = _anderson(np.array(xs), np.array(gs)), None
    inp.x0 = solved
    return solved


def _anderson(xs: np.ndarray, gs: np.ndarray) -> np.ndarray:
    """The next state of the fixed-point iteration x = g(x) from its history (rows: states tried,
    and their images), by Anderson's mixing: the image of the combination of the last states whose
    residuals g - x cancel best (least squares). The step map contracts with an alternating sign
    (about -0.16 a pass at 5 km/h): plain passes gain less than a digit each, mixing gains several."""
    f = gs - xs
    if len(xs) < 2:
        return gs[-1]
    d_f, d_g = np.diff(f, axis=0).T, np.diff(gs, axis=0).T
    gamma = np.linalg.lstsq(d_f, f[-1], rcond=None)[0]
    return gs[-1] - d_g @ gamma


def _speed_matched_start(controller: StepController, plan, inp: StepInput, tol: float) -> tuple:
    """Initial stance state whose hip leaves the step at the speed it entered it (secant method),
    and its solved stance."""
    con, theta2 = plan.constraints, controller.gains.theta2_ref
    mean = plan.constraints.step_length / plan.timings.t_step
    stances = {}

    def mismatch(speed):
        inp.x0 = _walking_state(con, speed, theta2)
        stances[speed] = stance = controller.solve_stance(plan, inp, 0)
        return stance_hip(controller.body, stance.final_state, np.zeros(2))[1][0] - speed

    v0 = 1.2 * mean
    f0 = mismatch(v0)
    # the second trial speed: the first of these whose stance has a solution (a stance that only
    # just locks its leg can have none at 1.35 of the mean speed: 1 km/h at 1.8 m in plain shooting)
    for ratio in (1.35, 1.05, 1.3, 1.1):
        try:
            v1 = ratio * mean
            f1 = mismatch(v1)
            break
        except ConvergenceError:
            if ratio == 1.1:
                raise
    for _ in range(30):
        if abs(f1) < tol or f1 == f0:
            break
        # a secant step limited to 20 % of the mean speed: far from the orbit the first stance
        # may have no solution at all
        step = float(np.clip(-f1 * (v1 - v0) / (f1 - f0), -0.2 * mean, 0.2 * mean))
        # a trial speed whose stance has no solution: go half as far, or past it (plain shooting
        # fails on narrow bands of speeds where a lock event meets a grid node; the mismatch itself
        # is smooth across them)
        for factor in (1.0, 0.5, 1.5, 0.25, 2.0, 0.125):
            trial = v1 + factor * step
            try:
                f_new = mismatch(trial)
                break
            except ConvergenceError:
                continue
        else:
            raise ConvergenceError(0, "stance", abs(f1), "no periodic start found (initial hip speed)")
        v0, v1, f0, f1 = v1, trial, f1, f_new
    return _walking_state(con, v1, theta2), stances[v1]
