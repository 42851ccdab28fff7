"""What each stage of a step hands on to the next (control/step.py, control/step_stages.py), on
solved walks in both solver modes. A stage can be wrong in a way the solvers absorb (curve P's
peak somewhere else, the swing fed a scaled hip acceleration): every walk still converges, and only
a stored reference walk would notice, until it is regenerated. These checks hold each stage to
what it promises instead."""
from __future__ import annotations

import math

import numpy as np
import pytest
from _walk_checks import record_walk

from klaw_ocp.control.stance_law import STANCE_CONTEXT
from klaw_ocp.control.swing_law import SWING_CONTEXT, curve_p
from klaw_ocp.dynamics import hip_kinematics, stance_accelerations, swing_accelerations
from klaw_ocp.dynamics.evaluate import evaluate
from klaw_ocp.kinematics.pelvis import PelvisSchedule

CONFIG = {"name": "stages", "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 4}}
START = {"name": "stages-start", "body": {"height": 1.7, "mass": 65},
         "walk": {"speed": 3.0, "steps": 3, "start_from_rest": True, "end_at_rest": True}}


def _recorded(config: dict, method: str):
    """The walk and the subphase problems its steps were solved from, with their solutions (the
    last solve of each step and subphase, _walk_checks.record_walk)."""
    recorded = record_walk(config, method)
    walk = recorded.walk
    assert [s.index for s in walk.steps] == list(range(len(walk.steps)))
    return walk, [(step, problem, solution) for (step, _), (problem, solution) in recorded.problems.items()]


@pytest.fixture(scope="module", params=["multiple-shooting", "plain-shooting"])
def walks(request):
    return [_recorded(config, request.param) for config in (CONFIG, START)]


def test_curve_p_peaks_at_swing_peak_position_of_its_travel(walks):
    """§4.3's five conditions, with C = swing_peak_position D: y(0) = a0, y(C) = a_max, y'(C) = 0,
    y(D) = a_min, and y'(D) the end slope that has the knee extending at t1 (the paper's 0; ours,
    issue #36: docs/paper-map.md), on every step of the walk; a closing step's C at most
    CLOSING_CURVE_P_PEAK D (control/step_stages.py)."""
    from klaw_ocp.control.step_stages import CLOSING_CURVE_P_PEAK
    for walk, _ in walks:
        for step in walk.steps:
            fraction = walk.spec.attributes.swing_peak_position
            if step.plan.constraints.closing:
                fraction = min(fraction, CLOSING_CURVE_P_PEAK)
            p = step.curve_p
            poly = np.poly1d(p["coefficients"])
            assert p["C"] == pytest.approx(fraction * p["D"], rel=1e-12), step.index
            assert 0 < p["C"] < p["D"]
            assert poly(0.0) == pytest.approx(p["a0"], abs=1e-12)
            assert poly(p["C"]) == pytest.approx(p["a_max"], abs=1e-12)
            assert poly.deriv()(p["C"]) == pytest.approx(0.0, abs=1e-9)
            assert poly(p["D"]) == pytest.approx(p["a_min"], abs=1e-12)
            assert poly.deriv()(p["D"]) == pytest.approx(p["end_slope"], abs=1e-9)
            assert -1.0 < p["end_slope"] < 0.0                         # descending: the knee extends
            assert p["a_max"] > max(p["a0"], p["a_min"])


def test_the_swing_models_read_the_curve_p_the_stage_planned(walks):
    """The swing context carries curve P's coefficients and origin: swing_law.curve_p evaluated on
    it is the stage's polynomial."""
    for walk, solved in walks:
        for step, problem, _ in solved:
            if problem.spec.name != "swing1":
                continue
            p = walk.steps[step].curve_p
            c = problem.context
            for s in np.linspace(0.0, p["D"], 5):
                assert float(curve_p(c, s)) == pytest.approx(np.polyval(p["coefficients"], s), abs=1e-12)
            assert c[SWING_CONTEXT.index["curve_x0"]] == p["x0"]


def _stance_part(body, problem, x, t, u):
    """What the stance model gives for the stance part of a swing state at ``t``: its forces (read
    from the swing's reported forces, which the swing computes from the solved stance
    parameters), then the stance accelerations and the hip's acceleration, computed here by the
    numeric dynamics API, not by the swing law."""
    forces = evaluate(problem.spec.outputs, x, t, u, problem.context)[0]
    locked = bool(problem.context[STANCE_CONTEXT.index["locked"]])
    qdd = stance_accelerations(body, x[0:3], x[3:6], forces[0:3], locked=locked)
    _, _, hip_acc = hip_kinematics(body, x[0:3], x[3:6], qdd)
    return forces, qdd, np.asarray(hip_acc, float)


def test_the_swing_sees_the_stance_models_hip_acceleration(walks):
    """Assumption 4 with the pelvis (§4.2): the swing leg hangs from the pelvis's other hip. At
    every node of every swing subphase, the swing's right-hand side equals the swing dynamics
    (Appendix A.2) driven by the hip acceleration of the stance model (Appendix A.1) at the same
    state plus the pelvis offset's (kinematics/pelvis.py, from the context's pelvis numbers), and
    its stance part the stance model's own rates."""
    checked = 0
    for walk, solved in walks:
        body = walk.spec.body
        for _, problem, solution in solved:
            name = solution.name          # (a closing step's swing2 too)
            if not name.startswith("swing"):
                continue
            u = np.array([solution.parameters[k] for k in problem.spec.unknown_names])
            for k in range(0, len(solution.t), 4):
                x, t = solution.states[k], solution.t[k]
                xdot = evaluate(problem.spec.rhs, x, t, u, problem.context)[0]
                forces, qdd, hip_acc = _stance_part(body, problem, x, t, u)
                c = {key: problem.context[i] for key, i in SWING_CONTEXT.index.items()}
                pelvis = PelvisSchedule(c["pelvis_width"], c["pelvis_rotation_start"], c["pelvis_rotation_end"],
                                        c["pelvis_list"], c["swing_end_time"])
                hip_acc = np.asarray(hip_acc) + np.array(pelvis.swing_hip_offset(t)[2])
                np.testing.assert_allclose(xdot[0:3], x[3:6], rtol=0, atol=1e-12)
                np.testing.assert_allclose(xdot[3:6], qdd, rtol=1e-9, atol=1e-9)
                if name == "swing1":      # the knee locked for the dynamics (eq. 5)
                    q, qd, locked = [x[6], x[7]], [x[8], 0.0], True
                elif name == "swing2":
                    q, qd, locked = x[6:8], x[8:10], False
                else:
                    q, qd, locked = [x[6], 0.0], [x[7], 0.0], True
                expected = swing_accelerations(body, q, qd, forces[4:6], hip_acc, locked=locked)
                np.testing.assert_allclose(xdot[-2 if name == "swing2" else -1:],
                                           expected if name == "swing2" else expected[:1],
                                           rtol=1e-9, atol=1e-9 * max(1.0, float(np.abs(expected).max())))
                checked += 1
    assert checked > 100


def test_swing1_starts_from_the_double_supports_toe_off(walks):
    """The double-support stage hands swing1 the hind leg's toe-off posture: its thigh and knee
    angles, and the stance state at toe-off."""
    for walk, solved in walks:
        for step, problem, solution in solved:
            if problem.spec.name != "swing1":
                continue
            s = walk.steps[step]
            stance = s.subphase("stance")
            t_to = s.double_support["t"][-1]
            k_to = int(np.argmin(np.abs(stance.t - t_to)))
            assert problem.x0[:6] == pytest.approx(stance.states[k_to], abs=1e-14)
            assert solution.t[0] == pytest.approx(t_to, abs=1e-12)
            assert problem.x0[6] == pytest.approx(s.double_support["theta3"][-1], abs=1e-12)
            assert math.isfinite(problem.x0[8])
