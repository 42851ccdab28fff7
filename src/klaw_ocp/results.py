"""Read-only views of a simulated :class:`~klaw_ocp.walk.Walk`: the per-sample table and the summary.

The table has one row per time sample, in walk time (s from the first heel strike):

- ``double_support`` rows: the stance nodes before toe-off; theta3/theta4 are the hind leg's
  kinematic angles (swing-model convention), their rates finite differences; F_theta3/F_theta4
  are NaN because that leg is not driven dynamically then.
- ``swing1``/``swing2``/``swing3`` rows: the integrated states of those subphases (the stance
  state rides along, see control/swing_law.py). In swing1 theta4d is the kinematic knee rate; in
  swing3 the knee is locked (theta4 = theta4d = 0).

hip_x/hip_y are world coordinates (m), x forward from the first stance ankle, y up from the ground.
``hip_y_ref`` is the vertical sinusoid the stance is guided towards at that instant (§4.2, world y):
lowest at the two heel strikes, a raised-cosine bump of the step's excursion in between.

The summary gives each step its ``stance_leg`` (step 0's stance leg is the right leg; the legs
alternate), its ``hip_reference`` (the sinusoid's heel-strike heights, excursion and the floor the
hip must not drop below, world y, m) and each subphase the unit of every parameter.
"""
from __future__ import annotations

import math

import casadi as ca
import numpy as np

from .control.parameter_units import parameter_unit
from .control.torques import hip_height_reference
from .dynamics import stance_hips
from .kinematics.swing_foot import sole_heights

COLUMNS = ("t", "step", "subphase", "w", "theta1", "theta2", "theta3", "theta4", "wd", "theta1d", "theta2d",
           "theta3d", "theta4d", "hip_x", "hip_y", "hip_y_ref", "F_w", "F_theta1", "F_theta2", "pa", "F_theta3", "F_theta4")


def _rows_for_step(step, body) -> list[dict]:
    rows = []
    stance = step.subphase("stance")
    ds = step.double_support
    rates3 = np.gradient(ds["theta3"], ds["t"]) if len(ds["t"]) > 1 else np.zeros(len(ds["t"]))
    rates4 = np.gradient(ds["theta4"], ds["t"]) if len(ds["t"]) > 1 else np.zeros(len(ds["t"]))

    ankle = np.array([step.origin_x, body.l9])

    def base(t, name, xs, forces, hip):
        return {"t": step.t_start + t, "step": step.index, "subphase": name,
                "w": xs[0], "theta1": xs[1], "theta2": xs[2], "wd": xs[3], "theta1d": xs[4], "theta2d": xs[5],
                "hip_x": hip[0], "hip_y": hip[1],
                "F_w": forces[0], "F_theta1": forces[1], "F_theta2": forces[2], "pa": forces[3]}

    # the stance state rides along in the swing states: every hip of the step in one call
    sizes = [len(sub.states) for sub in step.subphases]
    all_hips = np.split(stance_hips(body, np.vstack([sub.states[:, :6] for sub in step.subphases]), ankle)[0],
                        np.cumsum(sizes)[:-1])
    stance_hip_xy = all_hips[0]
    for k in range(len(ds["t"]) - 1):          # the toe-off node opens swing1
        row = base(ds["t"][k], "double_support", stance.states[k], stance.forces[k], stance_hip_xy[k])
        row.update(theta3=ds["theta3"][k], theta4=ds["theta4"][k], theta3d=rates3[k], theta4d=rates4[k],
                   F_theta3=float("nan"), F_theta4=float("nan"))
        rows.append(row)
    for sub, hips in zip(step.subphases[1:], all_hips[1:]):
        for k in range(len(sub.t)):
            if sub.name != "swing1" and k == 0:
                continue                          # same instant as the previous subphase's end
            x, f = sub.states[k], sub.forces[k]
            row = base(sub.t[k], sub.name, x, f, hips[k])
            if sub.name == "swing1":
                row.update(theta3=x[6], theta4=x[7], theta3d=x[8], theta4d=float("nan"))
            elif sub.name == "swing2":
                row.update(theta3=x[6], theta4=x[7], theta3d=x[8], theta4d=x[9])
            else:
                row.update(theta3=x[6], theta4=0.0, theta3d=x[7], theta4d=0.0)
            row.update(F_theta3=f[4], F_theta4=f[5])
            rows.append(row)
    # swing1 knee rate: the kinematic drive, by finite differences of theta4
    s1 = [r for r in rows if r["subphase"] == "swing1"]
    if len(s1) > 1:
        rates = np.gradient([r["theta4"] for r in s1], [r["t"] for r in s1])
        for r, v in zip(s1, rates):
            r["theta4d"] = float(v)
    for r, y in zip(rows, hip_reference_curve(step, body, np.array([r["t"] for r in rows]))):
        r["hip_y_ref"] = y
    return rows


def hip_reference_curve(step, body, t_world: np.ndarray) -> np.ndarray:
    """The hip-height sinusoid of ``step`` (§4.2) at walk times ``t_world``, world y (m); NaN for a
    step solved without one (a result from before it was recorded)."""
    ref = step.hip_reference
    if not ref:
        return np.full(len(t_world), np.nan)
    y, _ = hip_height_reference(ca.DM(np.asarray(t_world, float) - step.t_start), step.plan.timings.t_step,
                                ref["y_start"], ref["y_end"], ref["excursion"])
    return np.asarray(y, float).ravel() + body.l9


def stance_leg(index: int) -> str:
    """Which leg is the stance leg of step ``index``: step 0's is the right leg, then they alternate."""
    return "right" if index % 2 == 0 else "left"


def walk_table(walk) -> dict:
    """Column name -> array (``subphase`` is an array of str)."""
    rows = [r for step in walk.steps for r in _rows_for_step(step, walk.spec.body)]
    return _columns(rows)


def step_table(step, body) -> dict:
    """The rows of one step in :func:`walk_table`'s columns: a walk's table is its steps' tables
    one after the other (no row depends on a later step), so a run can write them as they come."""
    return _columns(_rows_for_step(step, body))


def _columns(rows: list[dict]) -> dict:
    return {c: np.array([r[c] for r in rows]) if c == "subphase" else np.array([r[c] for r in rows], float)
            for c in COLUMNS}


def _finite(value):
    value = float(value)
    return value if math.isfinite(value) else None


def hip_dip(body, stance) -> float:
    """How far the hip goes below the lower of its step's two heel-strike heights (0 if never):
    §4's "never … below its minimal value at heel strike", a hard constraint only in the
    tracking stance."""
    y = stance_hips(body, stance.states, np.zeros(2))[0][:, 1]
    return float(max(0.0, min(y[0], y[-1]) - y.min()))


def swing_foot_clearance(body, step) -> dict:
    """The swing foot's lowest toe tip and heel (m above the ground) at the swing's samples
    between toe-off and heel strike (both ends excluded: there the toe, then the heel, touch the
    ground by definition), and its lowest toe in swing2 (the mid-swing toe clearance that
    ``toe_clearance`` bounds). The foot is the body's (kinematics/swing_foot.py), on the leg
    interpolated linearly between the samples."""
    origin = np.array([step.origin_x, body.l9])
    subs = [step.subphase(name) for name in ("swing1", "swing2", "swing3")]
    t = np.concatenate([sub.t for sub in subs])
    x = np.vstack([sub.states[:, :7] for sub in subs])
    theta4 = np.concatenate([sub.states[:, 7] if sub.name != "swing3" else np.zeros(len(sub.t)) for sub in subs])
    hips = stance_hips(body, x[:, :6], origin)[0]
    shank = x[:, 6] + theta4
    ankle_y = hips[:, 1] - body.l3 * np.cos(x[:, 6]) - body.l4 * np.cos(shank)
    theta5, theta6 = step.swing_foot.grounded_angles(
        body, t, lambda times: (np.interp(times, t, ankle_y), np.interp(times, t, shank)))
    heel, toe = sole_heights(body, ankle_y, shank, theta5, theta6)
    inside = (t > t[0]) & (t < t[-1])
    swing2 = (t >= subs[1].t[0]) & (t <= subs[1].t[-1])
    return {"toe_min_m": float(toe[inside].min()), "heel_min_m": float(heel[inside].min()),
            "midswing_toe_min_m": float(toe[swing2].min())}


def foot_events(walk) -> list[dict]:
    """Every foot event of the walk, in time order: ``time`` (s, walk time), ``side`` (right or
    left) and ``event``: ``heel_strike``, ``foot_flat``, ``heel_off`` (the virtual leg's periods,
    §4.2) and ``toe_off`` (the end of the double support, t_ds after the other leg's heel strike).
    A walk from rest has no heel strike of its first stance leg, which stands flat from the start."""
    events = []
    for step in walk.steps:
        t0, side = step.t_start, stance_leg(step.index)
        other = "left" if side == "right" else "right"
        events.append({"time": t0 + step.plan.timings.t_ds, "side": other, "event": "toe_off"})
        foot = step.stance_foot
        if foot is None:
            continue
        if not foot.starts_standing:
            events.append({"time": t0, "side": side, "event": "heel_strike"})
        events.append({"time": t0 + foot.t_flat, "side": side, "event": "foot_flat"})
        events.append({"time": t0 + foot.t_heel_off, "side": side, "event": "heel_off"})
    order = {"heel_strike": 0, "foot_flat": 1, "heel_off": 2, "toe_off": 3}
    return sorted(events, key=lambda e: (e["time"], order[e["event"]]))


def step_summary(spec, step) -> dict:
    """One step's entry of the summary's ``steps`` (it does not change once the step is solved)."""
    entry = step.plan.as_dict()
    entry.update(stance_leg=stance_leg(step.index), origin_x_m=step.origin_x,
                 hind_ankle_x_m=step.hind_ankle_x, heel_clearance_min_m=step.heel_clearance_min,
                 hip_dip_m=hip_dip(spec.body, step.subphase("stance")), notes=list(step.notes),
                 swing_foot=swing_foot_clearance(spec.body, step),
                 curve_p={k: (v if isinstance(v, list) else float(v)) for k, v in step.curve_p.items()})
    if step.hip_reference:
        l9, ref = spec.body.l9, step.hip_reference
        entry["hip_reference"] = {"y_start_m": ref["y_start"] + l9, "y_end_m": ref["y_end"] + l9,
                                  "excursion_m": ref["excursion"],
                                  "floor_m": min(ref["y_start"], ref["y_end"]) + l9}
    entry["subphases"] = [{
        "name": s.name, "residual": _finite(s.residual), "iterations": int(s.iterations),
        "wall_s": float(s.wall_s), "parameters": {k: float(v) for k, v in s.parameters.items()},
        "units": {k: parameter_unit(k) for k in s.parameters},
        "success": bool(s.success), "message": s.message, "events": [list(e) for e in s.events],
        "path_min": _finite(s.path_min), "nlp": s.nlp, "fallbacks": list(s.fallbacks),
        "build_s": float(s.build_s),
    } for s in step.subphases]
    return entry


#: The summary's fields that time the run and change from run to run (in ``steps[].subphases[]``:
#: ``wall_s`` and ``build_s``); everything else is the same for the same config.
TIMING_FIELDS = ("wall_s", "real_time_factor")
SUBPHASE_TIMING_FIELDS = ("wall_s", "build_s")


def walk_summary(walk, table: dict | None = None, steps: list | None = None) -> dict:
    """The JSON-ready summary: status, method, body, timing and per-step subphase results
    (``table``: the walk's :func:`walk_table`, when the caller has it already; ``steps``: the
    :func:`step_summary` of every step, likewise)."""
    if steps is None:
        steps = [step_summary(walk.spec, step) for step in walk.steps]
    hip = (table if table is not None else walk_table(walk)) if walk.steps else None
    speed = (3.6 * (hip["hip_x"][-1] - hip["hip_x"][0]) / (hip["t"][-1] - hip["t"][0])
             if hip is not None and hip["t"][-1] > hip["t"][0] else None)
    return summary_of(walk, steps, speed)


def summary_of(walk, steps: list, mean_hip_speed_kmh) -> dict:
    """:func:`walk_summary` from its parts: the steps' entries and the mean hip speed (km/h)."""
    spec = walk.spec
    return {
        "name": spec.name, "status": walk.status, "message": walk.message,
        "failure": getattr(walk, "failure", None), "method": spec.method,
        "solver": {"intervals": spec.intervals, "tolerance": spec.tolerance, "nlp": spec.nlp,
                   "lock_rule": spec.lock_rule, "stance": spec.stance},
        "body": spec.body.as_dict(), "attributes": spec.attributes.as_dict(),
        "wall_s": walk.wall_s, "simulated_s": walk.duration,
        "real_time_factor": walk.duration / walk.wall_s if walk.wall_s > 0 else None,
        "steps_planned": len(spec.plans), "steps_completed": len(walk.steps),
        "start_from_rest": spec.start_from_rest, "end_at_rest": spec.end_at_rest,
        "mean_hip_speed_kmh": mean_hip_speed_kmh,
        "solver_messages": list(getattr(walk, "solver_messages", [])),
        "steps": steps,
        "events": foot_events(walk),
    }
