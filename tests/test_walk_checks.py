"""Walk-level checks, from the walk itself, over the envelope's coarse grid in both solver modes.

None of these trusts what a solver says about its own solution (``residual``, ``path_min`` at the
nodes, ``heel_clearance_min``): the heel-strike posture is rebuilt from the states with forward
kinematics and compared with eq. 3 computed here; the timings are eq. 2 computed here; the
trajectories between the stored samples are re-integrated with SciPy's DOP853 on the subphase's own
model (tests/_walk_checks.py), and the clearances and the hip height are measured on that dense
grid (8 samples per interval).
"""
import math

import numpy as np
import pytest
from scipy.integrate import solve_ivp

from _walk_checks import (COARSE, COARSE_IDS, METHODS, TOE_DIP_BETWEEN_NODES, coarse_walk, dense_trajectory,
                          eq2_timings, eq3_landing, record_walk, swing_ankle_heights, swing_body_lift, swing_foot_heights,
                          swing_leg_function, world_hip_velocities,
                          world_hips)
from klaw_ocp.dynamics import CONSERVED, heel_strike_conserved, heel_strike_map, swing_leg_points

SUBPHASES = ("stance", "swing1", "swing2", "swing3")
#: the monitored stance lets the hip dip below its heel-strike height just after impact
#: (docs/solvers.md: at most 5 mm over the envelope; 4.4 mm is the deepest on this grid)
MONITORED_HIP_DIP_MAX = 0.005
#: RK4 (4 substeps, 20 intervals) against DOP853 at rtol 1e-10, on one interval without a torque
#: switch at its end (m, rad, m/s, rad/s alike): below 1e-4 from 5 km/h up; below that speed the
#: intervals are long (up to 128 ms at 0.5 km/h, after the graded stance's dense start) and the
#: stance intervals where the leg spring takes the impact and rebounds are off by up to 7.3e-4 at
#: 0.5 km/h (7.1e-3 on the uniform grid; control/step.py's stance_grid) and 2.4e-4 at 3-4 km/h.
#: The most follows an unlock: in plain shooting step 1's stance at 0.5 km/h locks early and
#: unlocks at 0.93 s, and the released leg spring rebounds in the next interval, off by 9.8e-3 in
#: 87 ms on the uniform grid and by 1.3e-2 in 116 ms on the graded one
RK4_INTERVAL_ERROR = 2e-4
RK4_INTERVAL_ERROR_BELOW_5_KMH = 2e-2


@pytest.fixture(params=[(m, p) for m in METHODS for p in COARSE],
                ids=[f"{m}-{i}" for m in METHODS for i in COARSE_IDS])
def grid_walk(request):
    method, point = request.param
    recorded = coarse_walk(method, point)
    assert recorded.walk.status == "ok", recorded.walk.message
    return recorded


def _steps(recorded):
    return recorded.walk.steps


def test_every_heel_strike_is_the_eq3_posture(grid_walk):
    """At t_step the stance hip is where eq. 3 puts it, the swing leg is straight, and its heel
    touches the ground on the planned point, one step ahead of the stance ankle less l8."""
    body, attrs = grid_walk.body, grid_walk.walk.spec.attributes
    for step in _steps(grid_walk):
        sl = step.plan.constraints.step_length
        # the hip lead: the attribute from a dimensionless speed of 0.45 on, in proportion below
        v_star = step.plan.parameters.speed_kmh / 3.6 / math.sqrt(body.g * (body.l1 + body.l9))
        lead = attrs.heel_strike_hip_lead * min(1.0, v_star / 0.45)
        expected = eq3_landing(body, sl, attrs.theta5_impact, attrs.pelvic_rotation, lead)
        stance_end = step.subphase("stance").states[-1]
        hip = world_hips(body, stance_end[None, :], step.origin_x)[0]
        assert hip - [step.origin_x, body.l9] == pytest.approx(expected["hip"], abs=1e-7), step.index
        assert step.subphase("swing2").states[-1][7] == pytest.approx(0.0, abs=1e-7)   # knee straight at t2
        swing_end = step.subphase("swing3").states[-1]
        landing_hip = expected["landing_hip"] + [step.origin_x, body.l9]     # the pelvis's other hip
        foot = swing_leg_points(body, (swing_end[6], 0.0), landing_hip, math.radians(attrs.theta5_impact),
                                math.radians(attrs.theta6_impact))
        # Table B-1's l11 (eq. 3) and the foot's sqrt(l8² + l9²) agree to its 4 digits
        assert foot["heel"] == pytest.approx([step.origin_x + expected["heel_x"], 0.0], abs=5e-5), step.index


def test_every_subphase_lasts_what_eq2_says(grid_walk):
    """Stance 0..t_step, double support until t_ds, swing1/2/3 ending at 50/85/100 % of the swing,
    and steps that follow each other without gap or overlap."""
    t_walk = 0.0
    for step in _steps(grid_walk):
        eq2 = eq2_timings(step.plan.parameters.step_frequency_spm)
        assert step.t_start == pytest.approx(t_walk, abs=1e-12)
        spans = {s.name: (s.t[0], s.t[-1]) for s in step.subphases}
        assert spans["stance"] == pytest.approx((0.0, eq2["t_step"]), abs=1e-12)
        assert step.double_support["t"][-1] == pytest.approx(eq2["t_ds"], abs=1e-12)
        assert spans["swing1"] == pytest.approx((eq2["t_ds"], eq2["t1"]), abs=1e-12)
        assert spans["swing2"] == pytest.approx((eq2["t1"], eq2["t2"]), abs=1e-12)
        assert spans["swing3"] == pytest.approx((eq2["t2"], eq2["t_step"]), abs=1e-12)
        t_walk += eq2["t_step"]
    assert grid_walk.walk.duration == pytest.approx(t_walk, abs=1e-12)


def test_each_stance_starts_where_the_heel_strike_map_puts_it(grid_walk):
    """The stance origin advances by the step length, the hind leg's ankle is the previous stance
    ankle, and across heel strike the stance model's hip passes to the landing leg's hip (the
    pelvis's other one, l0 sin(rotation) ahead, kinematics/pelvis.py) with the hip's velocity, θ2
    and θ̇2 continuous, so the quantities the map conserves (dynamics.CONSERVED) are the same
    before, moved to that hip, and after."""
    body, steps = grid_walk.body, _steps(grid_walk)
    rotation = math.radians(grid_walk.walk.spec.attributes.pelvic_rotation)
    for before, after in zip(steps, steps[1:]):
        sl = before.plan.constraints.step_length
        shift = body.l0 * math.sin(rotation) if sl > 0 else 0.0
        assert before.plan.constraints.hip_shift == pytest.approx(shift, abs=1e-15)
        assert after.origin_x - before.origin_x == pytest.approx(sl, abs=1e-12)
        assert after.hind_ankle_x == pytest.approx(before.origin_x, abs=1e-12)
        pre, post = before.subphase("stance").states[-1], after.subphase("stance").states[0]
        assert post == pytest.approx(heel_strike_map(body, pre, (sl, 0.0), hip_shift=(shift, 0.0)), abs=1e-12)
        assert world_hips(body, post[None], after.origin_x) == pytest.approx(
            world_hips(body, pre[None], before.origin_x) + [shift, 0.0], abs=1e-12)
        assert world_hip_velocities(post[None]) == pytest.approx(world_hip_velocities(pre[None]), abs=1e-10)
        assert (post[2], post[5]) == pytest.approx((pre[2], pre[5]), abs=1e-14)
        old, new = np.array([before.origin_x + shift, body.l9]), np.array([after.origin_x, body.l9])
        kept = heel_strike_conserved(body, pre, old, about=new)
        now = heel_strike_conserved(body, post, new)
        for key in CONSERVED:
            assert np.asarray(now[key]) == pytest.approx(np.asarray(kept[key]), rel=1e-9, abs=1e-10), key


def test_the_hip_advances_one_step_length_per_step(grid_walk):
    """A step that starts from the mirror of an equal step's heel strike (every step after the
    first at a constant speed, and the first of a walk that starts walking) moves the pelvis's
    centre (the stance hip plus half the offset to the other hip, kinematics/pelvis.py) by sl, so
    the mean speed is sl·sf."""
    body, walk = grid_walk.body, grid_walk.walk
    steady = []
    for step in _steps(grid_walk):
        previous = walk.steps[step.index - 1].plan if step.index else None
        mirrored = (step.index == 0 and not walk.spec.start_from_rest) or (
            previous is not None and previous.constraints.step_length == step.plan.constraints.step_length)
        if not mirrored or step.plan.constraints.closing:
            continue
        states = step.subphase("stance").states
        hips = world_hips(body, states[[0, -1]], step.origin_x)
        (dx, _), _, _ = step.pelvis.swing_hip_offset(np.array([0.0, step.plan.timings.t_step]))
        centre = hips[:, 0] + dx / 2
        p = step.plan.parameters
        assert (centre[1] - centre[0]) / step.plan.timings.t_step == pytest.approx(
            p.step_length_m * p.step_frequency_spm / 60, rel=1e-7), step.index
        assert p.step_length_m * p.step_frequency_spm * 60 / 1000 == pytest.approx(p.speed_kmh, rel=1e-12)
        steady.append(step.index)
    if not walk.spec.start_from_rest:
        assert 0 in steady and 1 in steady


def test_the_hip_stays_above_its_heel_strike_floor(grid_walk):
    """§4: the hip "must never be allowed to drop below its minimal value at heel strike"; the
    paper's monitored stance approximates it by feedback, within MONITORED_HIP_DIP_MAX, checked on
    the dense grid of the stance."""
    body = grid_walk.body
    deepest = 0.0
    for step in _steps(grid_walk):
        y = world_hips(body, grid_walk.dense(step.index, "stance").x, step.origin_x)[:, 1]
        floor = min(y[0], y[-1])
        deepest = max(deepest, floor - y.min())
    assert deepest <= MONITORED_HIP_DIP_MAX


def test_the_tracking_stance_keeps_the_hip_on_its_floor_between_the_nodes():
    """The tracking stance holds the floor as a hard constraint at its nodes; between them the hip
    may not dip by more than a tenth of a millimetre."""
    recorded = record_walk({"name": "tracking", "body": {"height": 1.8, "mass": 80},
                            "walk": {"speed": 5.0, "steps": 3}, "solver": {"stance": "tracking"}},
                           "multiple-shooting")
    body = recorded.body
    for step in recorded.walk.steps:
        problem, solution = recorded.problems[(step.index, "stance")]
        y = world_hips(body, dense_trajectory(problem, solution).x, step.origin_x)[:, 1]
        floor = min(step.hip_reference["y_start"], step.hip_reference["y_end"]) + body.l9
        assert y.min() >= floor - 1e-4, step.index


def test_the_swing2_toe_keeps_its_clearance_between_the_nodes(grid_walk):
    """§4.3: the toe stays above ``toe_clearance`` through swing2, measured on the dense grid with
    the foot the swing defines (not the solver's path function), in every step but a walk's
    closing step, whose swing2 has no toe bound: its foot comes down in place beside the stance
    foot (control/swing_spec.py, swing2_closing), where the body's ground guard shows it
    (test_the_body_swing_foot_stays_above_the_ground_everywhere)."""
    body, clearance = grid_walk.body, grid_walk.walk.spec.attributes.toe_clearance
    for step in _steps(grid_walk):
        if step.index == len(grid_walk.walk.spec.plans):
            continue
        problem, _ = grid_walk.problems[(step.index, "swing2")]
        toe, _ = swing_foot_heights(body, step.origin_x, "swing2", problem.context,
                                    grid_walk.dense(step.index, "swing2"))
        assert toe.min() >= clearance - TOE_DIP_BETWEEN_NODES, step.index


def _swing_feet():
    """(where, whether the step is a walk's first step from rest or its closing step, ankle
    heights, lowest of the toe and heel of the dynamic leg's foot as the body turns it, the body's
    lift of the ankle) on the dense grid of every swing subphase of every step of the coarse grid
    in both modes."""
    for method in METHODS:
        for point in COARSE:
            recorded = coarse_walk(method, point)
            spec = recorded.walk.spec
            for step in recorded.walk.steps:
                leg, lift = swing_leg_function(recorded, step), swing_body_lift(recorded, step)
                starting_or_stopping = (step.index == 0 and spec.start_from_rest) or step.index == len(spec.plans)
                for name in SUBPHASES[1:]:
                    problem, _ = recorded.problems[(step.index, name)]
                    dense = recorded.dense(step.index, name)
                    toe, heel = swing_foot_heights(recorded.body, step.origin_x, name, problem.context, dense, leg)
                    ankle_y = swing_ankle_heights(recorded.body, step.origin_x, name, dense)
                    yield (f"{method} {point} step {step.index} {name}", starting_or_stopping, recorded.body,
                           ankle_y, np.minimum(toe, heel), lift(dense.t))


#: how far short of the ground's limits the smooth turn alone may fall where the ankle grazes l9 (m)
TURN_SHORTFALL = 1e-3


def test_the_turned_swing_foot_stays_above_the_ground_wherever_a_foot_fits():
    """Toe tip and heel of the dynamic leg's swing foot as the body turns it (body_motion/
    swing_foot_guard.py: the schedule, turned where it would enter the ground), before any lift, above
    the ground on the dense grid of swing1, swing2 and swing3, in every step of every walk of the
    coarse grid in both modes but first steps from rest and closing steps, wherever the ankle is
    at least l9 up (a flat foot fits there). Between the nodes, where swing2's toe clearance is a
    constraint, the foot may dip by TOE_DIP_BETWEEN_NODES; where the ankle grazes l9 the band of
    angles that fit is narrow and moves as the square root of the ankle's height above l9, faster
    than the guard's smooth turn follows (GUARD_RATE, GUARD_ACCELERATION), and the foot may dip by
    TURN_SHORTFALL more, which the ankle's lift takes (the next test: the body's foot everywhere)."""
    below, checked = [], 0
    for where, starting_or_stopping, body, ankle_y, lowest, _ in _swing_feet():
        fits = ankle_y >= body.l9
        if starting_or_stopping or not fits.any():
            continue
        checked += int(fits.sum())
        if lowest[fits].min() < -TOE_DIP_BETWEEN_NODES - TURN_SHORTFALL:
            below.append(f"{where}: {1000 * lowest[fits].min():.2f} mm")
    assert checked > 1000 and not below, "\n".join(below)


#: how far below its nodes' parabola the continuous model's lowest ankle may pass (m)
ANKLE_DIP_BETWEEN_NODES = 2e-4


def test_the_dynamic_swing_ankle_clears_l9_in_every_step():
    """Issue #36 item 6: the dynamic leg, hanging from the pelvis's other hip as it was solved, keeps
    its ankle at least l9 above the ground through swing2 and swing3 (where the shank passes under
    the knee) in every step of the coarse grid in both modes, first steps from rest and closing
    steps included, in the continuous model (the dense re-integration): the thigh's peak is planned
    ahead where it must be (control/swing_clearance.py), so the body lifts no foot there; a closing
    step's thigh comes in from behind (control.step_stages.CLOSING_APPROACH_DEG). Its ankle comes
    down onto l9 as both legs come upright, so it is also held to ANKLE_DIP_BETWEEN_NODES (1.2 mm
    below l9 at 9 km/h with the thigh vertical from t1 on)."""
    low, checked, planned = [], 0, 0
    for method in METHODS:
        for point in COARSE:
            recorded = coarse_walk(method, point)
            for step in recorded.walk.steps:
                planned += step.thigh_retraction_deg > 0
                for name in ("swing2", "swing3"):
                    dense = recorded.dense(step.index, name)
                    inside = dense.t < step.plan.timings.t_step - 1e-9
                    y = swing_ankle_heights(recorded.body, step.origin_x, name, dense, step.pelvis)[inside]
                    checked += len(y)
                    if y.min() < recorded.body.l9 - ANKLE_DIP_BETWEEN_NODES:
                        low.append(f"{method} {point} step {step.index} {name}: {1000 * (y.min() - recorded.body.l9):.2f} mm")
    assert checked > 1000 and planned > 0 and not low, "\n".join(low)


def test_the_body_swing_foot_stays_above_the_ground_everywhere():
    """The body's swing foot (turned, and lifted with the ankle by the knee's bend where the
    dynamic leg is too low for any foot: swing_foot_guard.lifted_foot) above the ground on the dense
    grid of every swing subphase of every step of the coarse grid in both modes, first steps from
    rest and closing steps included, where the dynamic ankle comes up to 30 mm below l9. A step
    whose turned foot clears the ground throughout is not lifted at all."""
    below, steps, lifted = [], {}, 0
    for where, _, body, ankle_y, lowest, lift in _swing_feet():
        feet = lowest + lift
        if feet.min() < -TOE_DIP_BETWEEN_NODES:
            below.append(f"{where}: {1000 * feet.min():.2f} mm")
        assert np.all(lift >= 0.0), where
        step = where.rsplit(" ", 1)[0]
        need, most = steps.get(step, (np.inf, 0.0))
        steps[step] = (min(need, lowest.min()), max(most, lift.max()))
        lifted += int((lift > 0).sum())
    assert lifted > 0 and not below, "\n".join(below)
    # (margins: the lowest point is measured on the dense samples, the lift on the guard grid)
    needless = [step for step, (need, most) in steps.items() if need >= TOE_DIP_BETWEEN_NODES and most > 1e-9]
    assert not needless, needless


def test_the_stored_trajectories_are_the_model_between_the_nodes(grid_walk):
    """Re-integrated from each stored sample, every smooth interval ends on the next stored sample
    to within the RK4 discretisation error."""
    for step in _steps(grid_walk):
        for name in SUBPHASES:
            problem, solution = grid_walk.problems[(step.index, name)]
            t_off = step.plan.timings.t_theta1_off
            gaps = [(k, g) for k, g in grid_walk.dense(step.index, name).gaps
                    if abs(solution.t[k + 1] - t_off) > 1e-12]
            allowed = RK4_INTERVAL_ERROR if step.plan.parameters.speed_kmh >= 5 else RK4_INTERVAL_ERROR_BELOW_5_KMH
            assert gaps and max(g for _, g in gaps) <= allowed, (step.index, name)


def _continuous_final_state(problem, solution):
    """The subphase re-integrated whole from its initial state with DOP853 and the solved
    parameters: the continuous model's answer to the same torques."""
    spec = problem.spec
    u = np.array([solution.parameters[k] for k in spec.unknown_names])
    run = solve_ivp(lambda t, x: np.asarray(spec.rhs(x, t, u, problem.context)).ravel(),
                    (solution.t[0], solution.t[-1]), solution.states[0], method="DOP853", rtol=1e-9, atol=1e-11)
    return run.y[:, -1]


def _eq3_miss_in_the_continuous_model(step, problem, solution) -> float:
    con = step.plan.constraints
    end = _continuous_final_state(problem, solution)
    return max(abs(end[0] - con.w), abs(end[1] - con.theta1))


def test_the_solved_torques_meet_eq3_in_the_continuous_model(grid_walk):
    """The stance's torques, re-integrated whole with DOP853 (no lock events), bring w and θ1 to
    eq. 3 within 1e-5 (m, rad) from 2 km/h up: the walk is the model's, not only the RK4's. The
    swing's re-simulated stance ends on the stance's own final state within 1e-4 in both modes
    (the RK4 on two grids differs by 3.4e-5 at most): in plain shooting it starts in the stance's
    lock state and, in the closing step, has no lock events either."""
    for step in _steps(grid_walk):
        problem, solution = grid_walk.problems[(step.index, "stance")]
        if step.plan.parameters.speed_kmh >= 2 and not solution.events:
            assert _eq3_miss_in_the_continuous_model(step, problem, solution) <= 1e-5, step.index
        stance_end = step.subphase("stance").states[-1]
        assert step.subphase("swing3").states[-1][:6] == pytest.approx(stance_end, abs=1e-4), step.index


def test_slow_walks_meet_eq3_in_the_continuous_model_too():
    """Below 2 km/h too, on the graded stance grid (control/step.py's stance_grid): 3.1e-6 at
    0.5 km/h and 1.1e-6 at 1 km/h. On the uniform grid, whose first interval took the heel-strike
    impact in up to 88 ms, the miss was 5.3e-4 and 2.6e-5."""
    misses = []
    for method in METHODS:
        for point in COARSE:
            recorded = coarse_walk(method, point)
            for step in recorded.walk.steps:
                problem, solution = recorded.problems[(step.index, "stance")]
                if step.plan.parameters.speed_kmh < 2 and not solution.events:
                    misses.append(_eq3_miss_in_the_continuous_model(step, problem, solution))
    assert misses and max(misses) <= 1e-5


def test_the_swing_hangs_from_this_steps_stance(grid_walk):
    """Assumption 4: the swing leg hangs from the hip of the stance of the same step. Swing1 starts
    from the stance state at toe-off, and each swing subphase starts where the previous ended."""
    for step in _steps(grid_walk):
        stance = step.subphase("stance")
        k_toe_off = int(np.argmin(np.abs(stance.t - step.double_support["t"][-1])))
        s1, s2, s3 = (step.subphase(n) for n in SUBPHASES[1:])
        assert s1.states[0][:6] == pytest.approx(stance.states[k_toe_off], abs=1e-14)
        assert s2.states[0][:9] == pytest.approx(s1.states[-1], abs=1e-14)
        assert s3.states[0][:7] == pytest.approx(s2.states[-1][:7], abs=1e-14)


WALKING_STARTS = [(m, p) for m in METHODS for p in COARSE if not p[3]]


@pytest.mark.parametrize("method, point", WALKING_STARTS,
                         ids=[f"{m}-{COARSE_IDS[COARSE.index(p)]}" for m, p in WALKING_STARTS])
def test_a_walk_that_starts_walking_starts_on_its_periodic_orbit(method, point):
    """The whole stance state at step 0's heel strike is the one the step hands on to step 1 (the
    periodic orbit, control.periodic_start), so step 1's stance is step 0's: same torques."""
    steps = coarse_walk(method, point).walk.steps
    first, second = (s.subphase("stance").states[0] for s in steps[:2])
    assert first == pytest.approx(second, abs=1e-6)
    same = lambda a, b: a.timings == b.timings and a.constraints.step_length == b.constraints.step_length
    if same(steps[1].plan, steps[0].plan):   # not the closing step of a walk that stops at once
        torques = [s.subphase("stance").parameters for s in steps[:2]]
        for name in ("F_theta1_magnitude", "pa_offset"):
            assert torques[0][name] == pytest.approx(torques[1][name], rel=1e-2, abs=1e-6), name
