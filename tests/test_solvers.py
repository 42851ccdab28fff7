"""Solvers (issue #4): grids, the two modes on one square problem, events, failures."""
import math

import numpy as np
import pytest

from klaw_ocp import Body
from klaw_ocp.control.gains import control_gains
from klaw_ocp.control.stance_law import STANCE_CONTEXT
from klaw_ocp.control.step import body_context
from klaw_ocp.control.stance_spec import stance_fixed, stance_spec, stance_unknowns
from klaw_ocp.errors import ConfigError
from klaw_ocp.gait import LocomotionAttributes, step_constraints, state_phase_timings
from klaw_ocp.solvers import PlainShootingSolver, SubphaseProblem, make_solver, time_grid


def test_time_grid_puts_breakpoints_on_nodes():
    grid = time_grid(0.0, 1.0, 20, [0.37, 0.5, 2.0])
    assert grid.size == 21 and grid[0] == 0 and grid[-1] == 1
    assert np.all(np.diff(grid) > 0)
    assert np.min(np.abs(grid - 0.37)) < 1e-15 and np.min(np.abs(grid - 0.5)) < 1e-15


def test_unknown_method_lists_the_choices():
    with pytest.raises(ConfigError, match="multiple-shooting.*plain-shooting"):
        make_solver("newton")


def stance_problem(speed_factor=1.33, theta1_target=None, x0=None, y_ref=None, **options):
    body, attrs = Body(1.8, 80), LocomotionAttributes.defaults()
    con = step_constraints(body, 0.7746, attrs)
    tim = state_phase_timings(107.58, attrs)
    g = control_gains(body, attrs)
    ctx = body_context(body)
    y = con.hip_y - body.l9 if y_ref is None else y_ref
    ctx.update(k_w=g.k_w, v_w=g.v_w, k_t=g.k_t, d_t=g.d_t, theta2_ref=0.0, k_y=g.k_y, c_y=g.c_y,
               t_off=tim.t_theta1_off, t_step=tim.t_step, y_start=y, y_end=y, excursion=0.04, hip_rise=0.5, hip_fall=0.5,
               hip_fall_power=1.0, locked=0.0, hip_settle=1.0,
               theta1_target=con.theta1 if theta1_target is None else theta1_target, w_target=con.w)
    v = speed_factor * con.step_length / tim.t_step
    if x0 is None:
        x0 = [con.w, -con.theta1, 0.0, -v * math.sin(con.theta1), v * math.cos(con.theta1) / con.w, 0.0]
    nu = len(stance_unknowns())
    return SubphaseProblem(stance_spec(), np.array(x0), time_grid(0, tim.t_step, 20, [tim.t_theta1_off]),
                           STANCE_CONTEXT.pack(ctx), np.zeros(nu), np.r_[40.0, np.full(nu - 1, 0.02)],
                           fixed=stance_fixed(), **options)


def stance_u(magnitude, offset=0.0):
    """A stance parameter vector with the pa profile at zero (the paper's formulation)."""
    return np.r_[magnitude, offset, np.zeros(len(stance_unknowns()) - 2)]


def test_both_modes_solve_the_same_square_problem_alike():
    pb = stance_problem()
    ms = make_solver("multiple-shooting").solve(pb)
    ps = make_solver("plain-shooting").solve(pb)
    assert ms.success and ps.success
    assert ms.residual < 1e-9 and ps.residual < 1e-9
    for key in ms.parameters:
        assert ps.parameters[key] == pytest.approx(ms.parameters[key], rel=1e-6)
    assert np.allclose(ms.states[-1], ps.states[-1], atol=1e-7)


def test_failure_comes_back_as_a_result_not_an_exception():
    pb = stance_problem(theta1_target=1.2)   # far from the guess: too few iterations to get there
    starved = [make_solver("multiple-shooting", max_iterations=1),
               PlainShootingSolver(max_iterations=3, max_sweeps=1)]
    for solver in starved:
        solver_result = solver.solve(pb)
        assert not solver_result.success and solver_result.status == "failed"
        assert solver_result.residual > 1e-6 and solver_result.message


def test_plain_shooting_locks_and_unlocks_the_leg():
    body = Body(1.8, 80)
    # the hip-height monitor asks for a hip above l1 while the hip is still behind the ankle
    pb = stance_problem(x0=[body.l1 - 0.005, -0.3, 0.0, 0.4, 1.6, 0.0], y_ref=body.l1 + 0.03)
    solver = PlainShootingSolver(intervals=20)
    times, states, context, log = solver.simulate(pb, stance_u(60.0))
    names = [name for name, _ in log]
    assert names[:2] == ["leg_too_long", "leg_vertical"], log
    t_lock, t_unlock = log[0][1], log[1][1]
    locked = (times >= t_lock) & (times <= t_unlock)
    assert np.allclose(states[locked, 0], body.l1, atol=1e-9)      # rigid leg at l1
    assert np.allclose(states[locked, 3], 0.0, atol=1e-12)         # wd = 0 while locked
    k_unlock = int(np.argmin(np.abs(times - t_unlock)))
    assert abs(states[k_unlock, 1]) < 1e-9                          # unlocked as theta1 crosses 0


@pytest.mark.parametrize("t0, t1, n, breakpoints", [
    (0.0, 0.55, 20, [0.1, 0.12, 0.3, 0.45]), (0.12, 0.4, 20, [0.2]), (0.12, 0.4, 20, [0.5]),
    (-0.0, 1.0, 3, [0.5, 0.5]), (0.3, 0.31, 1, []), (0.0, 1.0, 7, [0.999, 1e-3])])
def test_time_grid_is_the_linspace_of_each_segment_bit_for_bit(t0, t1, n, breakpoints):
    """time_grid builds every segment's nodes in one pass: the same numbers as np.linspace."""
    grid = time_grid(t0, t1, n, breakpoints)
    edges = [t0, *sorted(b for b in breakpoints if t0 + 1e-9 < b < t1 - 1e-9), t1]
    on_edges = np.flatnonzero(np.isin(grid, edges))
    assert len(grid) == n + 1
    expected = np.concatenate([[t0], *(np.linspace(grid[a], grid[b], b - a + 1)[1:]
                                       for a, b in zip(on_edges[:-1], on_edges[1:]) if b > a)])
    np.testing.assert_array_max_ulp(grid, expected, maxulp=1)      # numpy's linspace, to its last bit's rounding


def test_lead_nodes_start_the_grid_and_the_rest_is_the_plain_grid_of_what_is_left():
    grid = time_grid(0.0, 2.0, 20, [0.8, 0.9, 1.5], lead=(0.01, 0.05, 0.1))
    assert grid.size == 21 and grid[0] == 0.0 and grid[-1] == 2.0
    assert grid[1:4].tolist() == [0.02, 0.1, 0.2]
    assert grid[3:].tolist() == time_grid(0.2, 2.0, 17, [0.8, 0.9, 1.5]).tolist()
    assert time_grid(0.0, 2.0, 20, [0.8], lead=()).tolist() == time_grid(0.0, 2.0, 20, [0.8]).tolist()


@pytest.mark.parametrize("lead, breakpoints, n", [
    ((0.2, 0.1), [], 20), ((0.0, 0.1), [], 20), ((0.5, 1.0), [], 20),   # not increasing inside (0, 1)
    ((0.1, 0.3), [0.5], 20),                                              # a breakpoint among them
    ((0.1, 0.2, 0.3), [], 3)])                                            # no interval left for the rest
def test_lead_nodes_that_cannot_make_a_grid_are_refused(lead, breakpoints, n):
    with pytest.raises(ValueError):
        time_grid(0.0, 2.0, n, breakpoints, lead=lead)


def _stance_grid_of(body_height, speed_kmh, n=20):
    from klaw_ocp.control.step import StepController, stance_grid
    from klaw_ocp.gait import complete_parameters
    attrs = LocomotionAttributes.defaults()
    timings = state_phase_timings(complete_parameters(Body(body_height, 80), speed_kmh=speed_kmh).step_frequency_spm,
                                  attrs)
    breakpoints = StepController._breakpoints(type("Plan", (), {"timings": timings})())
    return stance_grid(timings.t_step, n, breakpoints), time_grid(0.0, timings.t_step, n, breakpoints)


@pytest.mark.parametrize("height", [1.4, 1.8, 2.1])
def test_stance_grids_from_2_kmh_up_are_the_uniform_ones_bit_for_bit(height):
    for speed in np.arange(2.0, 9.01, 0.25):
        graded, uniform = _stance_grid_of(height, speed)
        assert graded.tobytes() == uniform.tobytes(), speed


@pytest.mark.parametrize("height, speed", [(1.4, 1.0), (1.8, 0.5), (2.1, 0.5), (2.1, 1.5)])
def test_slow_stances_start_dense_after_heel_strike(height, speed):
    """30, 60, 100, 150 and 200 ms after heel strike (control/step.py's STANCE_IMPACT_NODES), then
    intervals up to the F_theta1 switch (0.4 t_step) at most 4/3 of the uniform interval, and after
    it on average at most 4/3 of it; a grid of 10 intervals, too few for that, stays uniform."""
    from klaw_ocp.control.step import GRADED_STANCE_STRETCH
    graded, uniform = _stance_grid_of(height, speed)
    t_step, h = uniform[-1], uniform[-1] / 20
    assert graded[1:6] == pytest.approx([0.03, 0.06, 0.10, 0.15, 0.20], abs=1e-15)
    switch = int(np.flatnonzero(graded == uniform[8])[0])      # the uniform grid's node 8 is 0.4 t_step
    assert np.diff(graded[5:switch + 1]).max() <= GRADED_STANCE_STRETCH * h
    assert (t_step - graded[switch]) / (20 - switch) <= GRADED_STANCE_STRETCH * h
    assert np.isin(uniform, graded).sum() >= 5          # the breakpoints are nodes of both
    few, uniform_few = _stance_grid_of(height, speed, n=10)
    assert few.tobytes() == uniform_few.tobytes()


def test_the_initial_guess_keeps_its_jacobian_for_the_next_solve():
    """The single-shooting steps of a cold guess keep their finite-difference Jacobian (as Newton
    keeps its own): a second problem of the subphase (here the periodic start's next trial speed)
    steps with it first, and solves to the same point as a solver that starts afresh."""
    first, second = stance_problem(speed_factor=1.2), stance_problem(speed_factor=1.35)
    solver = make_solver("multiple-shooting")
    assert solver.solve(first).success
    free = tuple(i for i, fixed in enumerate(first.fixed) if not fixed)
    assert (first.spec, free) in solver._guess_jacobians     # the cold guess needed its steps
    kept, fresh = solver.solve(second), make_solver("multiple-shooting").solve(second)
    assert kept.success and fresh.success and kept.residual < 1e-9
    for key in fresh.parameters:
        assert kept.parameters[key] == pytest.approx(fresh.parameters[key], rel=1e-8, abs=1e-9)


def test_a_kept_singular_jacobian_is_renewed_not_given_up_on():
    """Newton keeps its last Jacobian for the next solve (chord steps); one that is singular at the
    new start says nothing of it, so Newton renews it there instead of giving up (a walk's swing1
    failed so, at 1 km/h, where a fresh solver solved the same problem)."""
    from dataclasses import replace
    solver = make_solver("multiple-shooting")
    assert solver.solve(stance_problem()).success
    for newton in solver._newton.values():
        newton._last = {free: replace(lin, M_inv=None) for free, lin in newton._last.items()}
    again = solver.solve(stance_problem(speed_factor=1.35))
    assert again.success and again.fallbacks == [] and again.iterations > 0
