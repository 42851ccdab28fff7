"""The body's swing legs compiled (body_motion/swing_kernel.py, issue #38): every output the numpy
forms give (the swing's Hermite curves, leg_fk, the body's leg blended into the virtual legs,
the foot's schedules, knee_flexion_for_reach, the guard's ground window and required turn; after
the guard, the foot's points and the knee by leg_ik) to round-off, at every row the body hands
the kernels in walks across the envelope; CasADi's own evaluation the same."""
import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import motion, swing_kernel, swing_legs
from klaw_ocp.body_motion.kernel_forms import mapped_library
from klaw_ocp.body_motion.swing_foot_guard import _clip_to, _ground_window
from klaw_ocp.body_motion.walk_samples import hermite_sum
from klaw_ocp.dynamics.points import foot_points_arrays
from klaw_ocp.kinematics.leg_geometry import clamp, knee_flexion_for_reach, leg_fk, leg_ik, smoothstep
from klaw_ocp.kinematics.swing_foot import SCHEDULE_FIELDS, schedule_angles
from klaw_ocp.walk import simulate_walk
from test_stance_kernel import straight_leg_allowance

BODY = Body(height=1.8, mass=80.0)


def columns(rows, names):
    return {name: rows[:, i] for i, name in enumerate(names)}


def numpy_legs(rows) -> dict:
    """leg_function's outputs by the numpy forms (the body's swing leg before the kernel)."""
    x = columns(rows, swing_kernel.LEG_COLUMNS)
    h = x["u_1"] - x["u_0"]
    s = (x["u"] - x["u_0"]) / h
    theta3, theta4 = (hermite_sum(s, h, x[f"{v}_0"], x[f"rate{k}_0"], x[f"{v}_1"], x[f"rate{k}_1"])
                      for v, k in (("theta3", 3), ("theta4", 4)))
    model_hip, own = np.column_stack([x["model_hip_x"], x["model_hip_y"]]), np.column_stack([x["own_x"], x["own_y"]])
    model_shank, _, model_ankle = leg_fk(BODY, model_hip, theta3, theta4)
    schedule = {name: x[name] for name in SCHEDULE_FIELDS}
    tau = x["tau"]
    timed = schedule_angles(tau, schedule, clamp)[0]
    dynamic = np.hypot(*(model_ankle - model_hip).T)
    leaves = 1 - smoothstep((tau - x["t_toe_off"]) / (swing_kernel.TOE_OFF_BLEND * (x["t1"] - x["t_toe_off"])))
    lands = smoothstep((tau - x["t2"]) / np.maximum(x["t_heel_strike"] - x["t2"], 1e-12))
    towards = (model_ankle + leaves[:, None] * np.column_stack([x["toe_off_dx"], x["toe_off_dy"]])
               + lands[:, None] * np.column_stack([x["landing_dx"], x["landing_dy"]]) - own)
    reached = np.hypot(*towards.T)
    distance = dynamic + np.maximum(leaves, lands * lands) * (reached - dynamic)
    shank = model_shank + (leaves * x["toe_off_turn"] + lands * x["landing_turn"])
    ankle = own + towards * (distance / np.maximum(reached, 1e-12))[:, None]
    knee = knee_flexion_for_reach(BODY, np.hypot(*(ankle - own).T))
    theta5, theta6 = schedule_angles(tau, schedule, clamp, knee)
    window = _ground_window(BODY, theta6, ankle[:, 1], shank)
    return {"model_shank": model_shank, "model_ankle": model_ankle, "timed_theta5": timed, "shank": shank,
            "ankle": ankle, "knee": knee, "theta5": theta5, "theta6": theta6, "lowest": window[0],
            "highest": window[1], "fits": window[2], "level": window[3], "required": _clip_to(window, theta5) - theta5}


def numpy_feet(rows) -> dict:
    """foot_function's outputs by the numpy forms, and the knee's flexion there (the allowance's)."""
    x = columns(rows, swing_kernel.FOOT_COLUMNS)
    theta5, theta6 = schedule_angles(x["tau"], {name: x[name] for name in SCHEDULE_FIELDS}, clamp, x["knee"])
    theta5 = theta5 + x["turn"]
    ankle = np.column_stack([x["ankle_x"], x["ankle_y"]])
    heel, metatarsal, toe = foot_points_arrays(ankle, x["shank"], theta5, theta6, BODY.l8, BODY.l9, BODY.l12, BODY.l13)
    up = np.column_stack([np.zeros(len(theta5)), x["lift"]])
    _, theta4, knee = leg_ik(BODY, np.column_stack([x["own_x"], x["own_y"]]), ankle + up)
    return {"theta5": theta5, "theta6": theta6, "ankle": ankle + up, "heel": heel + up, "metatarsal": metatarsal + up,
            "toe": toe + up, "knee": knee}, theta4


@pytest.fixture(scope="module")
def handed():
    """The rows the body hands the kernels for four short walks (slow, fast, from rest to rest)."""
    legs, feet = [], []
    legs_at, feet_at = swing_legs.legs_at, swing_legs.feet_at
    swing_legs.legs_at = lambda rows, shared, ends=False: legs.append(rows) or legs_at(rows, shared, ends)
    swing_legs.feet_at = lambda rows, shared: feet.append(rows) or feet_at(rows, shared)
    try:
        for walk in ({"speed": 0.5, "steps": 5, "start_from_rest": True, "end_at_rest": True}, {"speed": 5.0, "steps": 4},
                     {"speed": 9.0, "steps": 4}, {"speed": 2.0, "steps": 4, "start_from_rest": True}):
            motion.body_motion(simulate_walk({"name": "kernel", "body": {"height": 1.8, "mass": 80.0}, "walk": walk}), 30.0)
    finally:
        swing_legs.legs_at, swing_legs.feet_at = legs_at, feet_at
    return np.vstack(legs), np.vstack(feet)


#: what a straight leg's inverse kinematics reads (test_stance_kernel.straight_leg_allowance): the
#: knee's flexion from the hip-ankle distance (the legs' "knee"; the foot that relaxes with it, θ5
#: and the turn it requires) and the knee the foot's ankle gives (the feet's "knee", x l3)
STRAIGHT_LEG_SENSITIVE = {"knee": 1.0, "theta5": 1.0, "required": 1.0}


def _close(got: dict, want: dict, tolerance: float = 1e-12, theta4=None, sensitive=STRAIGHT_LEG_SENSITIVE):
    """Each output of ``got`` within ``tolerance`` of ``want``'s, those ``sensitive`` (name -> its
    scale) within the straight leg's allowance at knee flexion ``theta4`` (want's "knee" where not
    given)."""
    allowance = straight_leg_allowance(BODY, want["knee"] if theta4 is None else theta4)
    for name, value in want.items():
        value = np.asarray(value, float)
        mine = np.asarray(got[name], float).reshape(value.shape)
        with np.errstate(invalid="ignore"):      # (the window's open ends: the same infinities)
            difference = np.abs(np.where(mine == value, 0.0, mine - value))
        limit = allowance * sensitive[name] + tolerance if name in sensitive else tolerance
        assert (difference.T <= limit).all(), (name, difference.max())


def test_the_legs_kernel_gives_the_numpy_forms(handed):
    rows, _ = handed
    got = swing_kernel.legs_at(rows, swing_kernel.constants(BODY))
    want = numpy_legs(rows)
    assert not want["fits"].all() and want["fits"].any() and (np.abs(want["required"]) > 0).sum() > 50
    _close(got, want)


def test_the_feet_kernel_gives_the_numpy_forms(handed):
    _, rows = handed
    got = swing_kernel.feet_at(rows, swing_kernel.constants(BODY))
    assert (rows[:, swing_kernel.FOOT_COLUMNS.index("lift")] > 0).any()    # an ankle lifted (the walks from rest)
    want, theta4 = numpy_feet(rows)
    _close(got, want, theta4=theta4, sensitive={"knee": BODY.l3})


def test_casadi_evaluation_gives_the_compiled_numbers(handed, monkeypatch):
    rows, _ = handed
    compiled = swing_kernel.legs_at(rows, swing_kernel.constants(BODY))
    monkeypatch.setenv("KLAW_OCP_JIT", "0")
    library = mapped_library(["test"], swing_kernel.leg_function, {"body_swing_legs": swing_kernel.LEG_BLOCK})
    kernel = library.functions()["body_swing_legs"]
    assert type(kernel).__name__ == "CasadiFunction"
    by_casadi = swing_kernel.evaluate(kernel, swing_kernel.LEG_BLOCK, rows, swing_kernel.constants(BODY),
                                      swing_kernel.LEG_OUTPUTS)
    _close(by_casadi, compiled, 1e-13)
