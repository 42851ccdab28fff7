"""The walk (issue #4): both solver modes, chained steps, acceptance properties on short walks."""

import numpy as np
import pytest

from _walk_checks import TOE_DIP_BETWEEN_NODES, dense_trajectory, record_walk, swing_foot_heights
from klaw_ocp.errors import ConvergenceError
from klaw_ocp.results import walk_summary, walk_table
from klaw_ocp.walk import simulate_walk

METHODS = ["multiple-shooting", "plain-shooting"]


def natural(steps=3, **walk):
    return {"name": "t", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": steps, **walk}}


@pytest.fixture(scope="module", params=METHODS)
def natural_walk(request):
    return simulate_walk(natural(3), method=request.param)


def test_every_subphase_meets_its_final_conditions(natural_walk):
    assert natural_walk.status == "ok"
    assert len(natural_walk.steps) == 3
    for step in natural_walk.steps:
        assert [s.name for s in step.subphases] == ["stance", "swing1", "swing2", "swing3"]
        for sub in step.subphases:
            assert sub.residual <= 1e-6, (step.index, sub.name, sub.residual)


def test_final_conditions_are_the_eq3_values(natural_walk):
    for step in natural_walk.steps:
        con = step.plan.constraints
        x = step.subphase("stance").final_state
        assert x[0] == pytest.approx(con.w, abs=1e-8)
        assert x[1] == pytest.approx(con.theta1, abs=1e-8)
        assert step.subphase("swing1").final_state[6] == pytest.approx(con.theta3, abs=1e-8)
        assert step.subphase("swing2").final_state[7] == pytest.approx(0.0, abs=1e-8)
        assert step.subphase("swing3").final_state[6] == pytest.approx(con.theta3, abs=1e-8)


def test_mean_speed_and_hip_sinusoid(natural_walk):
    table = walk_table(natural_walk)
    speed = 3.6 * (table["hip_x"][-1] - table["hip_x"][0]) / (table["t"][-1] - table["t"][0])
    assert speed == pytest.approx(5.0, rel=0.05)
    y = table["hip_y"]
    excursion = y.max() - y.min()
    assert 0.01 < excursion < 0.08
    # one minimum per step: the hip is lowest around heel strike, highest near mid-step
    for step in natural_walk.steps:
        rows = table["step"] == step.index
        t = table["t"][rows] - step.t_start
        ys = y[rows]
        interior = (t > 0.2 * step.plan.timings.t_step) & (t < 0.8 * step.plan.timings.t_step)
        assert ys[interior].min() > ys.min()
        assert ys[interior].max() == pytest.approx(ys.max())


def test_summary_reports_how_far_the_monitored_hip_dips(natural_walk):
    """The paper's monitored pa lets the hip dip below its heel-strike height just after impact
    (it arrives descending); the summary says by how much, per step."""
    summary = walk_summary(natural_walk)
    assert summary["solver"]["stance"] == "monitored"
    dips = [entry["hip_dip_m"] for entry in summary["steps"]]
    assert all(0.0 <= d < 0.005 for d in dips) and max(dips) > 1e-3
    assert all(s["nlp"] in ("rootfinder", "bisection-secant") for e in summary["steps"] for s in e["subphases"])


def test_summary_reports_each_steps_peak_swing_hip_torque(natural_walk):
    """Per step, the largest |F_theta3| over the swing subphases' nodes, swing2's first node
    included (its holding spring-damper takes over there), in N m and per kg of body mass."""
    summary = walk_summary(natural_walk)
    mass = natural_walk.spec.body.mass
    for step, entry in zip(natural_walk.steps, summary["steps"]):
        swings = [sub for sub in step.subphases if sub.name != "stance"]
        torques = np.concatenate([sub.forces[:, 4] for sub in swings])   # F_theta3 (SWING_FORCES)
        assert entry["peak_swing_hip_torque_N_m"] == pytest.approx(np.abs(torques).max(), rel=1e-12)
        assert entry["peak_swing_hip_torque_per_kg"] == pytest.approx(entry["peak_swing_hip_torque_N_m"] / mass)
        assert entry["peak_swing_hip_torque_N_m"] > 10.0   # a swing is driven
    # dynamics.csv keeps one sample at each subphase boundary: its swing torques never exceed it
    table = walk_table(natural_walk)
    for k, entry in enumerate(summary["steps"]):
        rows = (table["step"] == k) & np.isin(table["subphase"], ("swing1", "swing2", "swing3"))
        assert np.abs(table["F_theta3"][rows]).max() <= entry["peak_swing_hip_torque_N_m"] * (1 + 1e-12)


@pytest.mark.parametrize("method", METHODS)
def test_toe_clears_the_ground_in_swing2_and_the_heel_comes_down_onto_it_in_swing3(method):
    """Recomputed from the states, not read from the solver's path function at its 21 nodes: the
    toe and heel heights of the swing foot on a dense grid (8 samples per interval, re-integrated
    with DOP853), with the foot geometry. The toe stays above ``toe_clearance`` in swing2 (less
    what it may dip between the nodes), and the heel stays above the ground until it strikes.
    tests/test_walk_checks.py checks the whole swing over the envelope."""
    recorded = record_walk(natural(3), method)
    body, clearance = recorded.body, recorded.walk.spec.attributes.toe_clearance
    assert clearance == pytest.approx(0.015)
    for step in recorded.walk.steps:
        for name in ("swing2", "swing3"):
            problem, solution = recorded.problems[(step.index, name)]
            dense = dense_trajectory(problem, solution)
            assert len(dense.t) == 8 * (len(solution.t) - 1) + 1
            toe, heel = swing_foot_heights(body, step.origin_x, name, problem.context, dense)
            if name == "swing2":
                assert toe.min() >= clearance - TOE_DIP_BETWEEN_NODES, step.index
            else:
                assert heel.min() >= -1e-6, step.index
                assert abs(heel[-1]) < 5e-5      # it strikes at t_step (eq. 3; l11 to Table B-1's digits)


def test_both_modes_find_the_same_torques():
    walks = [simulate_walk(natural(2), method=m) for m in METHODS]
    for a, b in zip(walks[0].steps, walks[1].steps):
        for sa, sb in zip(a.subphases, b.subphases):
            for key, value in sa.parameters.items():
                other = sb.parameters[key]
                assert other == pytest.approx(value, rel=1e-6, abs=1e-7), (a.index, sa.name, key)
    ya, yb = (walk_table(w)["hip_y"] for w in walks)
    assert np.max(np.abs(ya - yb)) < 0.01


@pytest.mark.parametrize("method", METHODS)
def test_start_from_rest(method):
    walk = simulate_walk(natural(2, speed=2.0, start_from_rest=True), method=method)
    assert walk.status == "ok"
    x0 = walk.initial_state
    assert np.allclose(x0[3:], 0.0) and x0[1] == 0.0
    assert max(s.residual for step in walk.steps for s in step.subphases) <= 1e-6


def test_schedule_accelerates():
    cfg = natural(4)
    cfg["walk"]["schedule"] = [{"step": 0, "speed": 3.0}, {"step": 3, "speed": 5.0}]
    walk = simulate_walk(cfg)
    lengths = [s.plan.constraints.step_length for s in walk.steps]
    assert lengths == sorted(lengths) and lengths[-1] > lengths[0]
    assert max(s.residual for step in walk.steps for s in step.subphases) <= 1e-6


def test_failure_keeps_completed_steps(fail_at_step):
    fail_at_step(1, "swing2", 0.25)
    with pytest.raises(ConvergenceError) as info:
        simulate_walk(natural(3))
    err = info.value
    assert (err.step, err.subphase, err.residual) == (1, "swing2", 0.25)
    assert "step 1" in str(err) and "swing2" in str(err)
    assert len(err.partial.steps) == 1 and err.partial.status == "failed"
    summary = walk_summary(err.partial)
    assert summary["status"] == "failed" and summary["steps_completed"] == 1


@pytest.mark.parametrize("method", METHODS)
def test_start_and_stop_at_rest(method):
    """Fig. 8: a walk that starts standing and ends standing (closing step with sl = 0)."""
    walk = simulate_walk(natural(2, speed=2.0, start_from_rest=True, end_at_rest=True), method=method)
    assert walk.status == "ok" and len(walk.steps) == 3          # 2 planned steps + the closing step
    closing = walk.steps[-1]
    assert closing.plan.constraints.step_length == 0.0
    x = closing.subphase("stance").final_state
    body = walk.spec.body
    # standing over the ankle: eq. 3 with sl = 0 gives w = l1 (to Table B-1's rounding of l11)
    assert x[0] == pytest.approx(closing.plan.constraints.w, abs=1e-8) and abs(x[1]) < 1e-8
    assert x[0] == pytest.approx(body.l1, rel=1e-4)
    assert abs(x[4]) < 1e-8 and abs(x[3]) < 0.02                             # theta1d = 0, wd ~ 0
    assert "F_theta1_brake" in closing.subphase("stance").parameters
    assert max(s.residual for step in walk.steps for s in step.subphases) <= 1e-6


@pytest.mark.parametrize("rule", ["momentum", "zero"])
def test_the_lock_rule_is_set_from_the_config(rule):
    """``solver.lock_rule`` reaches the walk: the knee locks at t2 by that rule (eq. 5), so swing3
    starts from the knee-lock map of swing2's end, and the summary says which rule ran."""
    from klaw_ocp.dynamics import knee_lock_map
    walk = simulate_walk({**natural(2), "solver": {"lock_rule": rule}})
    assert walk.spec.lock_rule == rule and walk_summary(walk)["solver"]["lock_rule"] == rule
    for step in walk.steps:
        end2 = step.subphase("swing2").states[-1]
        start3 = step.subphase("swing3").states[0]
        locked = knee_lock_map(walk.spec.body, end2[6:10], np.zeros(2), rule)
        assert start3[7] == pytest.approx(locked[2], abs=1e-12)
        if rule == "zero":      # the paper: only the knee's rate is set to zero
            assert start3[7] == end2[8]
        else:
            # an impulse in the knee alone changes the thigh's rate too, in proportion to the
            # knee's rate when it locks; swing2 now brings the knee to rest (issue #36), so the
            # walk's lock changes nothing, and a knee still moving shows the rule at work
            assert abs(start3[7] - end2[8]) <= 1e-5
            moving = end2[6:10].copy()
            moving[3] = -5.0
            assert abs(knee_lock_map(walk.spec.body, moving, np.zeros(2), rule)[2] - moving[2]) > 0.1
