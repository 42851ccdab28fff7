"""How human is a walk: the sagittal figures gait laboratories report and the gait profile score
against published normative curves (docs/human-gait.md). ``benchmarks/bench_human.py`` prints them;
``tests/test_human_gait.py`` holds the walk to them.

- **Cycles.** A cycle runs from a heel strike to the next heel strike of the same leg
  (:func:`klaw_ocp.results.foot_events`); cycles that start in the walk's first ``start_steps``
  steps (the start) are left out.
- **Normative curves.** ``data/normative_sagittal_schwartz2008.csv``: the ensemble means and
  standard deviations of Schwartz, Rozumalski and Trost (2008) every 2 % of the cycle in five
  speed classes, each with its mean dimensionless speed v* = v / sqrt(g L). A walk's curves are
  interpolated linearly in v* between the two classes around its own (held at the end classes),
  with L the body's leg length, taken as its standing hip height l1 + l9.
- **Thigh.** The model's pelvis has no tilt (the pelvis's determinants are not in yet), so its hip
  flexion is the thigh's angle to the vertical. People's pelvis is tilted forward by about 10°,
  which their hip flexion includes; the normative thigh is therefore their hip flexion less their
  pelvic tilt.
- **Gait profile score** (Baker et al. 2009): a gait variable score (GVS) is the RMS difference
  between a cycle's curve and the normative mean over the 51 points 0, 2, ..., 100 % of the cycle;
  each side's GVS is the mean over its cycles; the GPS is the RMS of the GVSs of the sagittal
  thigh, knee and ankle of both legs (six).
"""
from __future__ import annotations

import math
from dataclasses import dataclass, field
from functools import lru_cache
from pathlib import Path

import numpy as np

from .body_motion.skeleton import ANGLE_NAMES
from .dynamics import stance_hips
from .gait.plan import dimensionless_speed

#: the normative table (its header says where it comes from)
NORMATIVE_CSV = Path(__file__).resolve().parent / "data" / "normative_sagittal_schwartz2008.csv"
#: the cycle's sample points (%), as in the table
CYCLE_PERCENT = np.arange(0.0, 101.0, 2.0)
#: the sagittal variables of the gait profile score
GPS_VARIABLES = ("thigh", "knee", "ankle")
SIDES = ("right", "left")
PREFIX = {"right": "r", "left": "l"}
COL = {name: i for i, name in enumerate(ANGLE_NAMES)}
#: the walk's first steps are its start: cycles starting in them are left out
START_STEPS = 2
#: the stance leg's angles whose rates :func:`stance_rate_jumps` checks
STANCE_JOINTS = ("hip_flexion", "knee_flexion", "ankle_dorsiflexion")
#: the frame rate of the rate-jump figure (a jump of 100 deg/s at 100 fps is 10^4 deg/s² of angular
#: acceleration held for one frame)
RATE_FPS = 100.0
#: the rate-jump figure leaves out the leg's landing: the frames whose stencil reaches within this
#: much (s) after the leg's own heel strike (the heel strike map, the foot coming down)
LANDING_WINDOW = 0.03
#: the angles :func:`limb_rate_jumps` checks, on both sides
LIMB_JOINTS = ("hip", "knee", "ankle", "toe", "shoulder", "elbow")
#: :func:`limb_rate_jumps` leaves out the frames whose stencil reaches within this much (s) after a
#: heel strike (the impact, and the landing foot still coming down 30-40 ms after it at 6 km/h:
#: the paper's telescope shortens at once) or reaches past one
AFTER_HEEL_STRIKE = 0.045


# ------------------------------------------------------------------------------------------
# the normative curves

@lru_cache(maxsize=1)
def normative_table() -> dict:
    """speed class -> {"v_star": float, column: (51,) array} from :data:`NORMATIVE_CSV`."""
    lines = [ln for ln in NORMATIVE_CSV.read_text(encoding="utf-8").splitlines() if ln and not ln.startswith("#")]
    header = lines[0].split(",")
    rows = [ln.split(",") for ln in lines[1:]]
    table: dict = {}
    for cls in dict.fromkeys(r[0] for r in rows):
        mine = np.array([[float(v) for v in r[1:]] for r in rows if r[0] == cls])
        entry = {name: mine[:, i] for i, name in enumerate(header[1:])}
        entry["v_star"] = float(mine[0, 0])
        entry["thigh"] = entry["hip_flexion"] - entry["pelvic_tilt"]
        entry["thigh_sd"] = entry["hip_sd"]
        table[cls] = entry
    return table


def normative_curves(v_star: float) -> dict:
    """The normative mean and sd curves at the dimensionless speed ``v_star``: variable (thigh,
    knee, ankle) -> (mean (51,), sd (51,)) at :data:`CYCLE_PERCENT`, linear in v* between the
    classes' mean speeds and held at the slowest and fastest."""
    classes = sorted(normative_table().values(), key=lambda e: e["v_star"])
    speeds = np.array([c["v_star"] for c in classes])
    v = float(np.clip(v_star, speeds[0], speeds[-1]))
    k = int(np.clip(np.searchsorted(speeds, v) - 1, 0, len(classes) - 2))
    w = (v - speeds[k]) / (speeds[k + 1] - speeds[k])
    names = {"thigh": ("thigh", "thigh_sd"), "knee": ("knee_flexion", "knee_sd"),
             "ankle": ("ankle_dorsiflexion", "ankle_sd")}
    return {var: tuple((1 - w) * classes[k][c] + w * classes[k + 1][c] for c in cols) for var, cols in names.items()}


# ------------------------------------------------------------------------------------------
# the walk's cycles

@dataclass(frozen=True)
class Cycle:
    """One gait cycle of one leg (walk times, s)."""
    side: str
    t0: float
    t1: float
    foot_flat: float
    heel_off: float
    toe_off: float

    def percent(self, t) -> np.ndarray:
        return 100 * (np.asarray(t, float) - self.t0) / (self.t1 - self.t0)

    def at(self, percent) -> np.ndarray:
        return self.t0 + np.asarray(percent, float) / 100 * (self.t1 - self.t0)


def steady_cycles(walk, t_last: float, start_steps: int = START_STEPS) -> list[Cycle]:
    """Every complete cycle of either leg that starts at step ``start_steps`` or later and ends
    by ``t_last`` (the last frame), with its own foot flat, heel-off and toe-off."""
    from .results import foot_events
    events = foot_events(walk)
    if len(walk.steps) <= start_steps:
        return []
    t_steady = walk.steps[start_steps].t_start - 1e-9
    cycles = []
    for side in SIDES:
        strikes = [e["time"] for e in events if e["side"] == side and e["event"] == "heel_strike"]
        for t0, t1 in zip(strikes[:-1], strikes[1:]):
            if t0 < t_steady or t1 > t_last + 1e-9:
                continue
            own = {ev: [e["time"] for e in events if e["side"] == side and e["event"] == ev and t0 < e["time"] < t1]
                   for ev in ("foot_flat", "heel_off", "toe_off")}
            if all(own.values()):
                cycles.append(Cycle(side, t0, t1, own["foot_flat"][0], own["heel_off"][0], own["toe_off"][0]))
    return cycles


def thigh_angle(leg) -> np.ndarray:
    """The thigh's sagittal angle to the vertical (hip -> knee projected on x-y), + knee ahead, deg."""
    d = leg.knee - leg.hip
    return np.degrees(np.arctan2(d[:, 0], -d[:, 1]))


def leg_curves(motion, side: str) -> dict:
    """The leg's sagittal angles at every frame (deg): thigh, hip flexion, knee, ankle."""
    deg = np.degrees(motion.angles)
    p = PREFIX[side]
    return {"thigh": thigh_angle(motion.legs[side]), "hip": deg[:, COL[f"{p}_hip_flexion"]],
            "knee": deg[:, COL[f"{p}_knee_flexion"]], "ankle": deg[:, COL[f"{p}_ankle_dorsiflexion"]],
            "shoulder": deg[:, COL[f"{p}_shoulder_flexion"]]}


# ------------------------------------------------------------------------------------------
# the figures

@dataclass
class HumanFigures:
    """The figures of one walk: each a list over its steady cycles (both legs), and the gait
    profile score. ``gvs``: (side, variable) -> GVS (deg)."""
    v_star: float
    cycles: list
    values: dict = field(default_factory=dict)
    gvs: dict = field(default_factory=dict)
    gps: float = math.nan
    #: (side, variable) -> the mean of the walk's cycles at CYCLE_PERCENT (deg)
    mean_curves: dict = field(default_factory=dict)

    def mean(self, key: str) -> float:
        v = np.asarray(self.values.get(key, []), float)
        v = v[np.isfinite(v)]
        return float(v.mean()) if v.size else math.nan

    def worst(self, key: str, high: bool = True) -> float:
        """The largest (``high``) or smallest value over the cycles."""
        v = np.asarray(self.values.get(key, []), float)
        v = v[np.isfinite(v)]
        return float(v.max() if high else v.min()) if v.size else math.nan


#: figure key -> (label, unit, typical band) of the figures :func:`human_figures` computes
FIGURES = {
    "knee_mid": ("knee flexion, most near 40 % (35-45 %)", "deg", (0.0, 10.0)),
    "knee_to": ("knee flexion at toe-off", "deg", (30.0, 50.0)),
    "knee_swing": ("knee flexion, swing peak", "deg", (55.0, 70.0)),
    "knee_swing_at": ("knee flexion, swing peak: when (% of cycle)", "%", (67.0, 77.0)),
    "thigh_min": ("thigh angle, most extended", "deg", (-20.0, -10.0)),
    "hip_range": ("hip flexion range", "deg", (38.0, 52.0)),
    "ankle_df": ("ankle, most dorsiflexed at 35-55 %", "deg", (8.0, 15.0)),
    "ankle_pf": ("ankle, most plantarflexed just after toe-off (+10 %)", "deg", (-25.0, -12.0)),
    "shoulder_range": ("shoulder flexion range", "deg", (30.0, 40.0)),
    "stance_jump": ("stance leg, largest rate jump at 100 fps (landing left out)", "deg/s", (0.0, 100.0)),
    "limb_jump": ("legs and arms, largest rate jump at 100 fps away from heel strikes", "deg/s", (0.0, 100.0)),
    "hip_surge": ("the hip's forward speed, range over the steady steps", "m/s", (0.2, 0.45)),
    "hip_decel": ("the hip's forward acceleration, least in the first 150 ms after heel strike", "m/s²", (-3.4, 0.0)),
}


def _window(t, t0, t1):
    return np.flatnonzero((t >= t0 - 1e-12) & (t <= t1 + 1e-12))


def stance_rate_jumps(motion, cycle: Cycle, fps: float = RATE_FPS) -> tuple[float, str, float]:
    """The largest frame-to-frame change of rate (deg/s) of the stance leg's sagittal angles
    (:data:`STANCE_JOINTS`) over the cycle's stance, at ``fps`` (frames at multiples of 1/fps from
    the heel strike, interpolated linearly in the motion's own frames, which must be finer): the
    rates over (k-1, k) and (k, k+1) of every frame k whose stencil lies in the stance and starts
    LANDING_WINDOW or more after the heel strike. Returns the jump, the angle and the % of the cycle."""
    p = PREFIX[cycle.side]
    t = cycle.t0 + LANDING_WINDOW + np.arange(0.0, cycle.toe_off - cycle.t0 - LANDING_WINDOW + 1e-12, 1 / fps)
    if len(t) < 3:
        return math.nan, "", math.nan
    deg = np.degrees(motion.angles)
    best = (0.0, "", math.nan)
    for joint in STANCE_JOINTS:
        a = np.interp(t, motion.t, deg[:, COL[f"{p}_{joint}"]])
        jump = np.abs(np.diff(a, 2)) * fps
        k = int(np.argmax(jump))
        if jump[k] > best[0]:
            best = (float(jump[k]), f"{p}_{joint}", float(cycle.percent(t[k + 1])))
    return best


def limb_rate_jumps(walk, motion, start_steps: int = START_STEPS, fps: float = RATE_FPS) -> tuple[float, str, float]:
    """The largest frame-to-frame change of rate (deg/s) at ``fps`` of any angle of the legs and
    arms (:data:`LIMB_JOINTS`, both sides) from the start of step ``start_steps`` to the last
    step's heel strike, frames at multiples of 1/fps interpolated in the motion's (finer) frames,
    leaving out the stencils that reach past a heel strike or start within AFTER_HEEL_STRIKE after
    one (issue #36's "anywhere except at heel strikes"). Returns the jump, the angle, its time (s)."""
    strikes = np.array([step.t_start for step in walk.steps])
    if len(strikes) <= start_steps + 1:
        return math.nan, "", math.nan
    t = np.arange(math.ceil(strikes[start_steps] * fps), math.floor(strikes[-1] * fps) + 1) / fps
    centre = t[1:-1, None]
    since = np.where(centre >= strikes, centre - strikes, np.inf).min(axis=1)
    until = np.where(centre < strikes, strikes - centre, np.inf).min(axis=1)
    away = (since - 1 / fps > AFTER_HEEL_STRIKE - 1e-9) & (until > 1 / fps + 1e-9)
    if not away.any():
        return math.nan, "", math.nan
    deg = np.degrees(motion.angles)
    best = (0.0, "", math.nan)
    for name, column in COL.items():
        if name[:2] in ("l_", "r_") and name[2:].split("_")[0] in LIMB_JOINTS:
            jump = np.abs(np.diff(np.interp(t, motion.t, deg[:, column]), 2)) * fps
            jump[~away] = 0.0
            k = int(np.argmax(jump))
            if jump[k] > best[0]:
                best = (float(jump[k]), name, float(t[k + 1]))
    return best


def hip_surge(walk, start_steps: int = START_STEPS, after_heel_strike: float = 0.15) -> tuple[float, float]:
    """The stance hip's forward speed (m/s) over the steps from ``start_steps`` on: its range, and
    its least rate of change (m/s²) within ``after_heel_strike`` s of each heel strike (issue #36:
    "the hip surges"; people: about 0.36 m/s peak to peak at 5 km/h, above -3.4 m/s²). From the
    stance states on every subphase's grid (the swings re-simulate the stance: a finer grid than
    the stance's own), by :func:`klaw_ocp.dynamics.stance_hips`."""
    body, speeds, decel = walk.spec.body, [], []
    for step in walk.steps[start_steps:]:
        t = np.concatenate([sub.t for sub in step.subphases])
        x = np.vstack([sub.states[:, :6] for sub in step.subphases])
        t, first = np.unique(t, return_index=True)
        v = stance_hips(body, x[first], np.zeros(2))[1][:, 0]
        speeds.append(v)
        early = t <= after_heel_strike
        if early.sum() >= 2:
            decel.append(float(np.min(np.diff(v[early]) / np.diff(t[early]))))
    if not speeds:
        return math.nan, math.nan
    return float(np.ptp(np.concatenate(speeds))), float(min(decel)) if decel else math.nan


def human_figures(walk, motion, start_steps: int = START_STEPS) -> HumanFigures:
    """The figures of ``walk`` with its body ``motion`` (:func:`klaw_ocp.body_motion.
    body_motion`, finer than :data:`RATE_FPS`) over its steady cycles."""
    plan = walk.steps[0].plan
    v_star = dimensionless_speed(walk.spec.body, plan.parameters.speed_kmh)
    cycles = steady_cycles(walk, float(motion.t[-1]), start_steps)
    out = HumanFigures(v_star, cycles, {key: [] for key in FIGURES})
    out.values["stance_jump_where"] = []
    norm = normative_curves(v_star)
    t = motion.t
    curves = {side: leg_curves(motion, side) for side in SIDES}
    sampled = {(side, var): [] for side in SIDES for var in GPS_VARIABLES}
    for c in cycles:
        leg = curves[c.side]
        idx = _window(t, c.t0, c.t1)
        pct = c.percent(t)
        mid = _window(pct, 35.0, 45.0)
        late = _window(pct, 35.0, 55.0)
        after = _window(t, c.toe_off, c.at(pct_of(c, c.toe_off) + 10.0))
        out.values["knee_mid"].append(float(leg["knee"][mid].max()))
        out.values["knee_to"].append(float(np.interp(c.toe_off, t, leg["knee"])))
        swing = _window(t, c.toe_off, c.t1)
        k = swing[int(np.argmax(leg["knee"][swing]))]
        out.values["knee_swing"].append(float(leg["knee"][k]))
        out.values["knee_swing_at"].append(float(pct[k]))
        out.values["thigh_min"].append(float(leg["thigh"][idx].min()))
        out.values["hip_range"].append(float(np.ptp(leg["hip"][idx])))
        out.values["ankle_df"].append(float(leg["ankle"][late].max()))
        out.values["ankle_pf"].append(float(leg["ankle"][after].min()))
        out.values["shoulder_range"].append(float(np.ptp(leg["shoulder"][idx])))
        jump, name, where = stance_rate_jumps(motion, c)
        out.values["stance_jump"].append(jump)
        out.values["stance_jump_where"].append((name, where))
        at = c.at(CYCLE_PERCENT)
        for var in GPS_VARIABLES:
            sampled[(c.side, var)].append(np.interp(at, t, leg[var]))
    for (side, var), rows in sampled.items():
        if rows:
            rows = np.array(rows)
            out.mean_curves[(side, var)] = rows.mean(axis=0)
            out.gvs[(side, var)] = float(np.mean(np.sqrt(np.mean((rows - norm[var][0]) ** 2, axis=1))))
    if out.gvs:
        out.gps = float(np.sqrt(np.mean(np.square(list(out.gvs.values())))))
    jump, name, when = limb_rate_jumps(walk, motion, start_steps)
    out.values["limb_jump"] = [jump]
    out.values["limb_jump_where"] = [(name, when)]
    surge, decel = hip_surge(walk, start_steps)
    out.values["hip_surge"], out.values["hip_decel"] = [surge], [decel]
    return out


def pct_of(cycle: Cycle, t: float) -> float:
    return float(cycle.percent(t))
