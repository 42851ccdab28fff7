"""Read-only views of a simulated :class:`~klaw_ocp.walk.Walk`: the per-sample table and the summary.

The table has one row per time sample, in walk time (s from the first heel strike):

- ``double_support`` rows: the stance nodes before toe-off; theta3/theta4 are the hind leg's
  kinematic angles (swing-model convention), their rates finite differences; F_theta3/F_theta4
  are NaN because that leg is not driven dynamically then.
- ``swing1``/``swing2``/``swing3`` rows: the integrated states of those subphases (the stance
  state rides along, see control/swing_law.py). In swing1 theta4d is the kinematic knee rate; in
  swing3 the knee is locked (theta4 = theta4d = 0).

hip_x/hip_y are world coordinates (m), x forward from the first stance ankle, y up from the ground:
the stance model's hip, the stance leg's (at each heel strike it passes to the landing leg's hip,
l0 sin(pelvic rotation) ahead). swing_hip_x/swing_hip_y are the pelvis's other hip
(:mod:`klaw_ocp.kinematics.pelvis`), from which the hind leg and then the swing leg hang.
``hip_y_ref`` is the vertical sinusoid the stance is guided towards at that instant (§4.2, world y):
lowest at the two heel strikes, a raised-cosine bump of the step's excursion in between.

The summary gives each step its ``stance_leg`` (step 0's stance leg is the right leg; the legs
alternate: :func:`klaw_ocp.gait.stance_leg`), its ``hip_reference`` (the sinusoid's heel-strike
heights, excursion and the floor the hip must not drop below, world y, m) and each subphase the
unit of every parameter.
"""
from __future__ import annotations

import numpy as np

from .body_motion.swing_foot_guard import guard_grid, lifted_feet, sole_heights
from .body_motion.walk_samples import gradient
from .control.parameter_units import parameter_unit
from .control.swing_law import SWING_FORCES
from .control.torques import hip_height_reference
from .dynamics import stance_hips
from .errors import finite_real
from .gait.attributes import STEP_ATTRIBUTES
from .gait.plan import stance_leg
from .kinematics.leg_geometry import leg_fk

COLUMNS = ("t", "step", "subphase", "w", "theta1", "theta2", "theta3", "theta4", "wd", "theta1d", "theta2d",
           "theta3d", "theta4d", "hip_x", "hip_y", "hip_y_ref", "swing_hip_x", "swing_hip_y", "F_w", "F_theta1", "F_theta2", "pa", "F_theta3", "F_theta4")


def hip_offsets(walk) -> list:
    """The hip less the stance ankle (n, 2) at every node of every subphase of every step
    ([step][subphase]), in one call of the stance kinematics: each step's stance state rides along
    in its swing states (a call per step or subphase costs more than the whole walk's hips)."""
    subs = [sub for step in walk.steps for sub in step.subphases]
    offsets = stance_hips(walk.spec.body, np.vstack([sub.states[:, :6] for sub in subs]), np.zeros(2))[0]
    offsets = iter(np.split(offsets, np.cumsum([len(sub.states) for sub in subs])[:-1]))
    return [[next(offsets) for _ in step.subphases] for step in walk.steps]


def step_hip_offsets(body, step) -> list:
    """:func:`hip_offsets` of one step ([subphase]), in one call of the stance kinematics."""
    # its pieces as plain slices, not np.split's (the served step's table: each numpy wrapper's
    # fixed cost is that function's time)
    offsets = stance_hips(body, np.concatenate([sub.states[:, :6] for sub in step.subphases]), np.zeros(2))[0]
    ends = np.cumsum([len(sub.states) for sub in step.subphases]).tolist()
    return [offsets[a:b] for a, b in zip([0, *ends[:-1]], ends)]


def _step_hips(body, step, step_offsets: list | None = None) -> list:
    """The world hip (n, 2) at every node of every subphase of one step ([subphase]), from its
    :func:`hip_offsets` when the caller has them."""
    if step_offsets is None:
        step_offsets = step_hip_offsets(body, step)
    return [np.array([step.origin_x, body.l9]) + offsets for offsets in step_offsets]


def walk_hips(walk, offsets: list | None = None) -> list:
    """The world hip (n, 2) at every node of every subphase of every step ([step][subphase])
    (``offsets``: the walk's :func:`hip_offsets`, when the caller has them)."""
    l9 = walk.spec.body.l9
    return [[np.array([step.origin_x, l9]) + hips for hips in step_offsets]
            for step, step_offsets in zip(walk.steps, hip_offsets(walk) if offsets is None else offsets)]


def _step_columns(step, hips: list) -> dict:
    """The table's columns (all but hip_y_ref) of one step, its hips from :func:`walk_hips`."""
    stance = step.subphase("stance")
    ds = step.double_support
    n = max(len(ds["t"]) - 1, 0)                # the toe-off node opens swing1
    rates = [gradient(ds[c], ds["t"]) if len(ds["t"]) > 1 else np.zeros(len(ds["t"]))
             for c in ("theta3", "theta4")]
    nan = np.full(n, np.nan)
    # per subphase: name, t, states, forces, hips, theta3, theta4, theta3d, theta4d, F_theta3, F_theta4
    parts = [("double_support", ds["t"][:n], stance.states[:n, :6], stance.forces[:n, :4], hips[0][:n],
              ds["theta3"][:n], ds["theta4"][:n], rates[0][:n], rates[1][:n], nan, nan)]
    for sub, sub_hips in zip(step.subphases[1:], hips[1:]):
        k = 0 if sub.name == "swing1" else 1     # else the same instant as the previous subphase's end
        x, f, t = sub.states[k:], sub.forces[k:], sub.t[k:]
        if sub.name == "swing1":
            # the knee rate: the kinematic drive, by finite differences of theta4
            rate = gradient(x[:, 7], step.t_start + t) if len(t) > 1 else np.full(len(t), np.nan)
            angles = (x[:, 6], x[:, 7], x[:, 8], rate)
        elif sub.name == "swing2":
            angles = (x[:, 6], x[:, 7], x[:, 8], x[:, 9])
        else:
            zero = np.zeros(len(t))
            angles = (x[:, 6], zero, x[:, 7], zero)
        parts.append((sub.name, t, x[:, :6], f[:, :4], sub_hips[k:], *angles, f[:, 4], f[:, 5]))
    joined = lambda i: np.concatenate([p[i] for p in parts])
    x, f, hip = joined(2), joined(3), joined(4)
    t = step.t_start + joined(1)
    # the pelvis's other hip, from which the hind leg and then the swing leg hang (§4.2)
    swing_hip = step.pelvis.swing_side_hips(joined(1), hip)
    columns = {"t": t, "step": np.full(len(t), float(step.index)),
               "swing_hip_x": swing_hip[:, 0], "swing_hip_y": swing_hip[:, 1],
               "w": x[:, 0], "theta1": x[:, 1], "theta2": x[:, 2], "wd": x[:, 3], "theta1d": x[:, 4],
               "theta2d": x[:, 5], "hip_x": hip[:, 0], "hip_y": hip[:, 1],
               "F_w": f[:, 0], "F_theta1": f[:, 1], "F_theta2": f[:, 2], "pa": f[:, 3]}
    columns.update(zip(("theta3", "theta4", "theta3d", "theta4d", "F_theta3", "F_theta4"),
                       map(joined, range(5, 11))))
    columns["subphase"] = [name for p in parts for name in [p[0]] * len(p[1])]
    return columns


def hip_reference_curve(step, body, t_world: np.ndarray) -> np.ndarray:
    """The hip-height sinusoid of ``step`` (§4.2) at walk times ``t_world``, world y (m); NaN for a
    step solved without one (a result from before it was recorded)."""
    return _hip_reference_curves([step], body, [np.asarray(t_world, float)])[0]


def _hip_reference_curves(steps, body, times: list) -> list:
    """:func:`hip_reference_curve` of each of ``steps`` at its walk times (one numpy evaluation of
    the formula the stance solves with, for them all)."""
    ref = [bool(step.hip_reference) for step in steps]
    out = [np.full(len(t), np.nan) for t in times]
    if not any(ref):
        return out
    sizes = [len(t) for t, r in zip(times, ref) if r]
    per_row = lambda f: np.repeat([f(step) for step, r in zip(steps, ref) if r], sizes).astype(float)
    t_local = np.concatenate([np.asarray(t, float) - step.t_start for step, t, r in zip(steps, times, ref) if r])
    shape = [per_row(lambda s, k=k: s.hip_reference[k]) for k in ("y_start", "y_end", "excursion")]
    # (a result from before the bump's shape was recorded had the paper's mid-step sinusoid)
    shape += [per_row(lambda s, k=k, v=v: s.hip_reference.get(k, v)) for k, v in (("rise", 0.5), ("fall", 0.5), ("power", 1.0), ("settle", 1.0))]
    y, _ = hip_height_reference(t_local, per_row(lambda s: s.plan.timings.t_step), *shape)
    values = iter(np.split(y + body.l9, np.cumsum(sizes)[:-1]))
    for i, r in enumerate(ref):
        if r:
            out[i] = next(values)
    return out


def walk_table(walk, offsets: list | None = None) -> dict:
    """Column name -> array (``subphase`` is an array of str); ``offsets``: the walk's
    :func:`hip_offsets`, when the caller has them."""
    steps = [_step_columns(step, hips) for step, hips in zip(walk.steps, walk_hips(walk, offsets))]
    references = _hip_reference_curves(walk.steps, walk.spec.body, [columns["t"] for columns in steps])
    for columns, y in zip(steps, references):
        columns["hip_y_ref"] = y
    return {c: np.array([v for columns in steps for v in columns[c]]) if c == "subphase" else
            np.concatenate([columns[c] for columns in steps]).astype(float) for c in COLUMNS}


def step_table(step, body, step_offsets: list | None = None) -> dict:
    """The rows of one step in :func:`walk_table`'s columns: a walk's table is its steps' tables
    one after the other (no row depends on a later step), so a run can write them as they come
    (``step_offsets``: its :func:`hip_offsets`, when the caller has them)."""
    columns = _step_columns(step, _step_hips(body, step, step_offsets))
    columns["hip_y_ref"] = _step_hip_reference(step, body, columns["t"])
    # every column is a new array or a view of one made here (np.concatenate always makes one):
    # float ones are kept, not copied again
    return {c: np.array(list(columns[c])) if c == "subphase" else np.asarray(columns[c]).astype(float, copy=False)
            for c in COLUMNS}


def _step_hip_reference(step, body, t_world: np.ndarray) -> np.ndarray:
    """:func:`_hip_reference_curves` of one step: the same formula on the same per-row arrays
    (each a value repeated; np.full's, not np.repeat's wrapper), without the walk's grouping."""
    n = len(t_world)
    if not step.hip_reference:
        return np.full(n, np.nan)
    ref = step.hip_reference
    row = lambda v: np.full(n, v, dtype=float)
    shape = [row(ref[k]) for k in ("y_start", "y_end", "excursion")]
    shape += [row(ref.get(k, v)) for k, v in (("rise", 0.5), ("fall", 0.5), ("power", 1.0), ("settle", 1.0))]
    y, _ = hip_height_reference(np.asarray(t_world, float) - step.t_start, row(step.plan.timings.t_step), *shape)
    return y + body.l9


def hip_dip(body, stance, offsets: np.ndarray | None = None) -> float:
    """How far the hip goes below the lower of its step's two heel-strike heights (0 if never):
    §4's "never … below its minimal value at heel strike", a hard constraint only in the
    tracking stance (``offsets``: the stance's :func:`hip_offsets`, when the caller has them)."""
    y = (stance_hips(body, stance.states, np.zeros(2))[0] if offsets is None else offsets)[:, 1]
    return float(max(0.0, min(y[0], y[-1]) - y.min()))


def swing_foot_clearance(body, step, hips: list | None = None) -> dict:
    """The swing foot's lowest toe tip and heel (m above the ground) at the swing's samples
    between toe-off and heel strike (both ends excluded: there the toe, then the heel, touch the
    ground by definition), and its lowest toe in swing2 (the mid-swing toe clearance that
    ``toe_clearance`` bounds). The foot is the body's (body_motion/swing_foot_guard.py: turned,
    and lifted with the ankle where the dynamic leg is too low for a foot), on the leg interpolated
    linearly between the samples (``hips``: the step's :func:`walk_hips`, when the caller has
    them); ``ankle_lift_max_m`` is how far the body lifted the ankle above the dynamic leg's."""
    return swing_foot_clearances(body, [step], [hips])[0]


def swing_foot_clearances(body, steps: list, hips: list) -> list[dict]:
    """:func:`swing_foot_clearance` of each of ``steps`` (``hips[k]`` may be None), every step's
    foot in one pass (:func:`klaw_ocp.body_motion.swing_foot_guard.lifted_feet`)."""
    names = ("swing1", "swing2", "swing3")
    legs = [_swing_leg(body, step, step_hips, names) for step, step_hips in zip(steps, hips)]
    grids = [guard_grid(step.swing_foot) for step in steps]
    on_grids = [[np.interp(grid, t, v) for v in (*hip.T, *ankle.T, shank)]
                for grid, (t, hip, ankle, shank) in zip(grids, legs)]
    stacked = np.concatenate(on_grids, axis=1)
    theta5, theta6, lift = lifted_feet(body, [step.swing_foot for step in steps], [leg[0] for leg in legs],
                                       grids, stacked[0:2].T, stacked[2:4].T, stacked[4])
    # the heights and their minima of every step at once too (minima are exact in any grouping)
    t = np.concatenate([leg[0] for leg in legs])
    counts = [len(leg[0]) for leg in legs]
    heel, toe = sole_heights(body, np.concatenate([leg[2][:, 1] for leg in legs]) + lift,
                             np.concatenate([leg[3] for leg in legs]), theta5, theta6)
    starts = np.cumsum([0, *counts[:-1]])
    first, last = np.repeat(t[starts], counts), np.repeat(t[starts + np.array(counts) - 1], counts)
    inside = (t > first) & (t < last)
    swing2 = np.array([(step.subphase("swing2").t[0], step.subphase("swing2").t[-1]) for step in steps])
    swing2 = (t >= np.repeat(swing2[:, 0], counts)) & (t <= np.repeat(swing2[:, 1], counts))
    lowest = lambda values, where: np.minimum.reduceat(np.where(where, values, np.inf), starts).tolist()
    names = ("toe_min_m", "heel_min_m", "midswing_toe_min_m", "ankle_lift_max_m")
    values = (lowest(toe, inside), lowest(heel, inside), lowest(toe, swing2), np.maximum.reduceat(lift, starts).tolist())
    return [dict(zip(names, entry)) for entry in zip(*values)]


def _swing_leg(body, step, hips, names):
    """The dynamic swing leg at the step's samples of the subphases ``names``: times (n,), the
    hip and the ankle (n, 2), the shank angle θ3 + θ4 (n,)."""
    subs = [step.subphase(name) for name in names]
    t = np.concatenate([sub.t for sub in subs])
    x = np.vstack([sub.states[:, :7] for sub in subs])
    theta4 = np.concatenate([sub.states[:, 7] if sub.name != "swing3" else np.zeros(len(sub.t)) for sub in subs])
    if hips is None:
        hips = stance_hips(body, x[:, :6], np.array([step.origin_x, body.l9]))[0]
    else:
        hips = np.vstack([h for sub, h in zip(step.subphases, hips) if sub.name in names])
    # the swing leg hangs from the pelvis's other hip (kinematics/pelvis.py), as it was solved
    hips = step.pelvis.swing_side_hips(t, hips)
    shank, _, ankle = leg_fk(body, hips, x[:, 6], theta4)
    return t, hips, ankle, shank


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
        foot = step.stance_foot      # the rules its own stance fixed: foot flat, heel-off
        if not foot.starts_standing:
            events.append({"time": t0, "side": side, "event": "heel_strike"})
        events.append({"time": t0 + foot.t_flat, "side": side, "event": "foot_flat"})
        events.append({"time": t0 + foot.t_heel_off, "side": side, "event": "heel_off"})
    order = {"heel_strike": 0, "foot_flat": 1, "heel_off": 2, "toe_off": 3}
    return sorted(events, key=lambda e: (e["time"], order[e["event"]]))


def step_summary(spec, step, step_offsets: list | None = None, swing_foot: dict | None = None) -> dict:
    """One step's entry of the summary's ``steps`` (it does not change once the step is solved);
    ``step_offsets``: its hip offsets (:func:`hip_offsets`), ``swing_foot`` its
    :func:`swing_foot_clearance`, when the caller has them."""
    if step_offsets is None:
        step_offsets = step_hip_offsets(spec.body, step)
    if swing_foot is None:
        swing_foot = swing_foot_clearance(spec.body, step, _step_hips(spec.body, step, step_offsets))
    stance = [sub.name for sub in step.subphases].index("stance")
    entry = step.plan.as_dict()
    # the attributes a step may have of its own (a schedule's), as it walked with them
    entry["attributes"] = {name: step.plan.attributes.get(name) for name in STEP_ATTRIBUTES}
    # the thigh's peak ahead of its heel-strike angle: the attribute, or more where the swing leg
    # needed it to clear the ground (control/swing_clearance.py)
    entry["thigh_retraction_deg"] = float(step.thigh_retraction_deg)
    entry.update(stance_leg=stance_leg(step.index), origin_x_m=step.origin_x,
                 hind_ankle_x_m=step.hind_ankle_x, heel_clearance_min_m=step.heel_clearance_min,
                 **peak_swing_hip_torque(step, spec.body.mass),
                 hip_dip_m=hip_dip(spec.body, step.subphases[stance], step_offsets[stance]), notes=list(step.notes),
                 swing_foot=swing_foot,
                 curve_p={k: (v if isinstance(v, list) else float(v)) for k, v in step.curve_p.items()})
    if step.hip_reference:
        l9, ref = spec.body.l9, step.hip_reference
        entry["hip_reference"] = {"y_start_m": ref["y_start"] + l9, "y_end_m": ref["y_end"] + l9,
                                  "excursion_m": ref["excursion"],
                                  "floor_m": min(ref["y_start"], ref["y_end"]) + l9}
    entry["subphases"] = [{
        "name": s.name, "residual": finite_real(s.residual), "iterations": int(s.iterations),
        "wall_s": float(s.wall_s), "parameters": {k: float(v) for k, v in s.parameters.items()},
        "units": {k: parameter_unit(k) for k in s.parameters},
        "success": bool(s.success), "message": s.message, "events": [list(e) for e in s.events],
        "path_min": finite_real(s.path_min), "nlp": s.nlp, "fallbacks": list(s.fallbacks),
        "build_s": float(s.build_s),
    } for s in step.subphases]
    return entry


#: the swing hip torque's column in a swing subphase's forces
_F_THETA3 = SWING_FORCES.index("F_theta3")


def swing_hip_torque_peak(step) -> tuple[float, str, float]:
    """The swing hip torque F_θ3 (N m) of largest magnitude over a step's swing subphases at their
    nodes (each subphase's first node included: where swing2's holding spring-damper takes over
    at t1, the torque can jump), its subphase and its time (s, from the step's heel strike)."""
    best = (0.0, "", float("nan"))
    for sub in step.subphases:
        if sub.name == "stance" or not len(sub.forces):
            continue
        k = int(np.argmax(np.abs(sub.forces[:, _F_THETA3])))
        if abs(sub.forces[k, _F_THETA3]) > abs(best[0]):
            best = (float(sub.forces[k, _F_THETA3]), sub.name, float(sub.t[k]))
    return best


def peak_swing_hip_torque(step, mass: float) -> dict:
    """summary.json's peak swing hip torque of a step (:func:`swing_hip_torque_peak`): N m, and per
    kg of body mass (people's peaks near 1 N m/kg at 5 km/h: docs/human-gait.md)."""
    peak = abs(swing_hip_torque_peak(step)[0])
    return {"peak_swing_hip_torque_N_m": peak, "peak_swing_hip_torque_per_kg": peak / mass}


def walk_summary(walk, table: dict | None = None, steps: list | None = None, offsets: list | None = None) -> dict:
    """The JSON-ready summary: status, method, body, timing and per-step subphase results
    (``table``: the walk's :func:`walk_table`, when the caller has it already; ``steps``: the
    :func:`step_summary` of every step, ``offsets``: its :func:`hip_offsets`, likewise)."""
    if steps is None:
        if offsets is None:
            offsets = hip_offsets(walk) if walk.steps else []
        # every step's swing foot in one pass (a pass per step costs mostly numpy's fixed overheads)
        feet = swing_foot_clearances(walk.spec.body, walk.steps, walk_hips(walk, offsets)) if walk.steps else []
        steps = [step_summary(walk.spec, step, step_offsets, foot)
                 for step, step_offsets, foot in zip(walk.steps, offsets, feet)]
    hip = (table if table is not None else walk_table(walk, offsets)) if walk.steps else None
    return summary_of(walk, steps, mean_hip_speed_kmh(hip, hip) if hip is not None else None)


def mean_hip_speed_kmh(first: dict, last: dict):
    """The mean hip speed (km/h) from the first row of the table ``first`` to the last of ``last``
    (tables as :func:`walk_table` makes them; one walk's, or its first and last steps'), None
    for no time between them."""
    if last["t"][-1] <= first["t"][0]:
        return None
    return 3.6 * (last["hip_x"][-1] - first["hip_x"][0]) / (last["t"][-1] - first["t"][0])


def summary_of(walk, steps: list, mean_hip_speed_kmh) -> dict:
    """:func:`walk_summary` from its parts: the steps' entries and the mean hip speed (km/h)."""
    spec = walk.spec
    return {
        "name": spec.name, "status": walk.status, "message": walk.message,
        "failure": getattr(walk, "failure", None), "method": spec.method,
        "solver": {"intervals": spec.intervals, "tolerance": spec.tolerance, "nlp": spec.nlp,
                   "lock_rule": spec.lock_rule, "stance": spec.stance},
        "body": spec.body.as_dict(), "attributes": spec.attributes.as_dict(),
        # the frame rate of angles.csv, walk.bvh and walk.mot (output.fps), for a reader of the folder
        "fps": float(spec.fps),
        # wall_s is the walk's own time; compile_s the one-off compiling of the solver kernels
        # that a first walk on a machine adds (0.0 with them cached), left out of wall_s and so
        # of the real-time factor
        "wall_s": walk.wall_s, "compile_s": float(getattr(walk, "compile_s", 0.0)), "simulated_s": walk.duration,
        "real_time_factor": walk.duration / walk.wall_s if walk.wall_s > 0 else None,
        "steps_planned": len(spec.plans), "steps_completed": len(walk.steps),
        "start_from_rest": spec.start_from_rest, "end_at_rest": spec.end_at_rest,
        "mean_hip_speed_kmh": mean_hip_speed_kmh,
        "solver_messages": list(getattr(walk, "solver_messages", [])),
        "steps": steps,
        "events": foot_events(walk),
    }
