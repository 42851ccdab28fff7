"""Benchmark: how human is the simulated walk? Gait figures beside healthy-adult values.

    cd /work/wt-body && PYTHONPATH=src python benchmarks/bench_human.py [CONFIG] [--steps 10] [--fps 200]

For the natural walk (configs/natural_walk.yaml: 1.8 m, 80 kg) at 3, 5 and 6 km/h it simulates a
short walk (``--steps``, default 10), puts the body on it (``body_motion`` at ``--fps``,
default 200) and measures, over the steady gait cycles (heel strike to the next heel strike of
the same leg, both legs; cycles that start in the first two steps are the start and are left
out), the figures gait labs measure people by: knee, thigh, hip and ankle angles at and between
the foot events, pelvic excursions, arm swing, event timings, rate jumps at the subphase
boundaries and the peak swing hip torque. Each figure is printed as mean ± sd over the cycles
beside the typical healthy-adult band (docs/human-gait.md gives the definitions and the
sources), then one verdict line per figure. It reports only: nothing is asserted, and a walk
that fails to converge is reported as such.
"""
from __future__ import annotations

import argparse
import math
import sys
import time
from copy import deepcopy
from dataclasses import dataclass
from pathlib import Path

import numpy as np
import yaml

import klaw_ocp
from klaw_ocp.body_motion import body_motion
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES
from klaw_ocp.human_gait import GPS_VARIABLES, human_figures
from klaw_ocp.results import foot_events, swing_hip_torque_peak

ROOT = Path(__file__).resolve().parents[1]
SPEEDS_KMH = (3.0, 5.0, 6.0)
START_STEPS = 2                 # steps 0 and 1 are the start of the walk
PREFIX = {"right": "r", "left": "l"}
OTHER = {"right": "left", "left": "right"}
LEG_JOINTS = ("hip_flexion", "hip_adduction", "hip_rotation", "knee_flexion", "ankle_dorsiflexion",
              "toe_dorsiflexion")
COL = {name: i for i, name in enumerate(ANGLE_NAMES)}


@dataclass(frozen=True)
class Figure:
    key: str
    label: str
    unit: str
    low: float          # the typical healthy-adult band (verdict: within if low <= value <= high)
    high: float
    typical: str        # as printed
    speed_dependent: bool = False
    digits: int = 1


FIGURES = (
    Figure("knee_lr", "knee flexion, loading-response peak (0-15 %)", "deg", 15, 20, "15 to 20", True),
    Figure("knee_mid", "knee flexion, most near 40 % (35-45 %)", "deg", 0, 10, "0 to 10"),
    Figure("knee_to", "knee flexion at toe-off", "deg", 30, 50, "30 to 50", True),
    Figure("knee_swing", "knee flexion, swing peak", "deg", 60, 65, "60 to 65", True),
    Figure("knee_swing_at", "  when (% of cycle)", "%", 70, 73, "70 to 73"),
    Figure("thigh_hs", "thigh angle at heel strike (+ forward)", "deg", 20, 25, "20 to 25", True),
    Figure("thigh_min", "thigh angle, most extended", "deg", -20, -10, "-20 to -10", True),
    Figure("hip_hs", "hip flexion at heel strike", "deg", 20, 35, "20 to 35", True),
    Figure("hip_ext", "hip flexion, peak extension", "deg", -15, -5, "-15 to -5", True),
    Figure("hip_range", "hip flexion range", "deg", 38, 52, "38 to 52", True),
    Figure("ankle_df", "ankle, most dorsiflexed at 35-55 %", "deg", 8, 15, "8 to 15"),
    Figure("ankle_pf", "ankle, most plantarflexed, toe-off to +10 %", "deg", -25, -12, "-25 to -12", True),
    Figure("pelvis_list", "pelvic list, half range (+/-)", "deg", 3, 5, "3 to 5"),
    Figure("pelvis_rot", "pelvic rotation, half range (+/-)", "deg", 3, 6, "3 to 6", True),
    Figure("lateral", "pelvis lateral displacement, range", "cm", 4, 5, "4 to 5"),
    Figure("arm_range", "shoulder flexion range", "deg", 30, 40, "30 to 40", True),
    Figure("arm_phase", "shoulder vs same-side hip, phase", "deg", 150, 180, "150 to 180"),
    Figure("foot_flat", "foot flat", "%", 8, 12, "8 to 12"),
    Figure("heel_off", "heel-off", "%", 30, 40, "30 to 40"),
    Figure("toe_off", "toe-off", "%", 60, 62, "60 to 62", True),
    Figure("jump_main", "leg rate jump at heel strikes/toe-offs", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("jump_other", "leg rate jump, other boundaries", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("jump_foot", "  own leg at foot flat, heel-off, toe-off", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("jump_hind", "  hind leg at the other leg's heel strike", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("stance_jump", "stance leg rate jump (100 fps)", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("limb_jump", "legs and arms, away from heel strikes", "deg/s", 0, 100, "<= 100", digits=0),
    Figure("hip_surge", "hip forward speed, range", "m/s", 0.2, 0.45, "about 0.36", digits=2),
    Figure("hip_decel", "hip deceleration after heel strike", "m/s2", -3.4, 0, ">= -3.4", digits=1),
    Figure("hip_torque", "peak swing hip torque per kg", "N m/kg", 0, 1.0, "<= 1.0", digits=2),
    Figure("gvs_thigh", "GVS thigh (RMS vs normative)", "deg", 0, 8, "<= 8 (people ~5)", True),
    Figure("gvs_knee", "GVS knee", "deg", 0, 8, "<= 8 (people ~5)", True),
    Figure("gvs_ankle", "GVS ankle", "deg", 0, 8, "<= 8 (people ~5)", True),
    Figure("gps", "gait profile score, sagittal (Baker 2009)", "deg", 0, 8, "<= 8 (people 5-6)", True),
)


# ------------------------------------------------------------------------------------------
# the walks

def speed_config(base: dict, speed: float, steps: int) -> dict:
    cfg = deepcopy(base)
    cfg["name"] = f"human_{speed:g}kmh".replace(".", "_")
    cfg["walk"].update(speed=speed, step_length=None, step_frequency=None, duration=None, steps=steps)
    cfg["output"] = {"plots": False, "animation": False}
    return cfg


def interp(t, bm_t, values):
    return float(np.interp(t, bm_t, values))


def window(bm_t, t0, t1):
    """Frame indices with t0 <= t <= t1."""
    return np.flatnonzero((bm_t >= t0 - 1e-12) & (bm_t <= t1 + 1e-12))


def first_harmonic_phase(t, values, t0, period) -> float:
    """Phase (rad) of the cycle-frequency Fourier component of ``values`` over one cycle."""
    w = 2 * math.pi * (t - t0) / period
    return float(np.angle(np.sum((values - values.mean()) * np.exp(-1j * w))))


def thigh_angle(leg) -> np.ndarray:
    """Sagittal angle of the thigh (hip -> knee, projected on x-y) to the vertical, + knee ahead, deg."""
    d = leg.knee - leg.hip
    return np.degrees(np.arctan2(d[:, 0], -d[:, 1]))


def rate_jump(angles_deg: np.ndarray, t: np.ndarray, fps: float, tb: float) -> np.ndarray:
    """|rate after - rate before| (deg/s) of each column at boundary time ``tb``: the rates from
    the two frames just before and the two just after, a frame at ``tb`` itself left out."""
    eps = 1e-9
    before = np.flatnonzero(t < tb - eps)
    after = np.flatnonzero(t > tb + eps)
    if len(before) < 2 or len(after) < 2:
        return np.full(angles_deg.shape[1], np.nan)
    i, j = before[-1], after[0]
    left = (angles_deg[i] - angles_deg[i - 1]) * fps
    right = (angles_deg[j + 1] - angles_deg[j]) * fps
    return np.abs(right - left)


def measure(walk, fps: float) -> dict:
    """Each figure's values over the steady cycles, and some details."""
    bm = body_motion(walk, fps)
    t = bm.t
    deg = np.degrees(bm.angles)
    events = foot_events(walk)
    steps = walk.steps
    t_steady = steps[START_STEPS].t_start - 1e-9
    mass = walk.spec.body.mass
    vals = {f.key: [] for f in FIGURES}
    cycles = []
    for side in ("right", "left"):
        p = PREFIX[side]
        hs = [e["time"] for e in events if e["side"] == side and e["event"] == "heel_strike"]
        for t0, t1 in zip(hs[:-1], hs[1:]):
            if t0 < t_steady or t1 > t[-1] + 1e-9:
                continue
            T = t1 - t0
            own = {ev: [e["time"] for e in events if e["side"] == side and e["event"] == ev and t0 < e["time"] < t1]
                   for ev in ("foot_flat", "heel_off", "toe_off")}
            if not all(own.values()):
                continue
            t_ff, t_ho, t_to = own["foot_flat"][0], own["heel_off"][0], own["toe_off"][0]
            cycles.append((side, t0, t1))
            pct = lambda x: 100 * (x - t0) / T
            idx = window(t, t0, t1)
            knee = deg[:, COL[f"{p}_knee_flexion"]]
            hip = deg[:, COL[f"{p}_hip_flexion"]]
            thigh = thigh_angle(bm.legs[side])
            lr = window(t, t0, t0 + 0.15 * T)
            vals["knee_lr"].append(knee[lr].max())
            sw = window(t, t_to, t1)
            k = sw[np.argmax(knee[sw])]
            vals["knee_swing"].append(knee[k])
            vals["knee_swing_at"].append(pct(t[k]))
            vals["thigh_hs"].append(interp(t0, t, thigh))
            vals["hip_hs"].append(interp(t0, t, hip))
            vals["hip_ext"].append(hip[idx].min())
            lst, rot = deg[idx, COL["pelvis_list"]], deg[idx, COL["pelvis_rotation"]]
            vals["pelvis_list"].append((lst.max() - lst.min()) / 2)
            vals["pelvis_rot"].append((rot.max() - rot.min()) / 2)
            z = bm.root[idx, 2]
            vals["lateral"].append(100 * (z.max() - z.min()))
            sh = deg[:, COL[f"{p}_shoulder_flexion"]]
            vals["arm_range"].append(sh[idx].max() - sh[idx].min())
            one = idx[t[idx] < t1 - 1e-9]       # one period, the end sample left out
            if np.ptp(sh[one]) > 1e-9 and np.ptp(hip[one]) > 1e-9:
                d = first_harmonic_phase(t[one], sh[one], t0, T) - first_harmonic_phase(t[one], hip[one], t0, T)
                vals["arm_phase"].append(abs(math.degrees(math.atan2(math.sin(d), math.cos(d)))))
            vals["foot_flat"].append(pct(t_ff))
            vals["heel_off"].append(pct(t_ho))
            vals["toe_off"].append(pct(t_to))
    # rate jumps: every leg angle at every boundary inside the steady cycles
    t_lo = min(c[1] for c in cycles) if cycles else math.inf
    t_hi = max(c[2] for c in cycles) if cycles else -math.inf
    leg_cols = [COL[f"{PREFIX[s]}_{j}"] for s in ("right", "left") for j in LEG_JOINTS]
    leg_deg = deg[:, leg_cols]
    leg_names = [ANGLE_NAMES[c] for c in leg_cols]
    main = [(e["time"], f"{e['side']} {e['event']}") for e in events if e["event"] in ("heel_strike", "toe_off")]
    other = [(e["time"], f"{e['side']} {e['event']}") for e in events if e["event"] in ("foot_flat", "heel_off")]
    for s in steps:
        swing_side = OTHER["right" if s.index % 2 == 0 else "left"]
        for name in ("swing2", "swing3"):
            other.append((s.t_start + float(s.subphase(name).t[0]), f"{swing_side} {name} start"))
    worst = {}
    for key, boundaries in (("jump_main", main), ("jump_other", other)):
        best, per_boundary = (0.0, "", ""), []
        for tb, what in boundaries:
            if not (t_lo - 1e-9 <= tb <= t_hi + 1e-9):
                continue
            j = rate_jump(leg_deg, t, fps, tb)
            if np.all(np.isnan(j)):
                continue
            m = int(np.nanargmax(j))
            per_boundary.append((tb, float(j[m])))
            if j[m] > best[0]:
                best = (float(j[m]), leg_names[m], f"{what} at t = {tb:.3f} s")
        worst[key] = best
        for _, t0, t1 in cycles:        # each cycle's largest, over the boundaries in [t0, t1)
            inside = [j for tb, j in per_boundary if t0 - 1e-9 <= tb < t1 - 1e-9]
            if inside:
                vals[key].append(max(inside))
    # the leg's own foot-period boundaries, and the hind leg at the other leg's heel strike, each on
    # the angles of the leg concerned only (issue #34's goal: continuous rates there)
    own_leg = {side: [COL[f"{PREFIX[side]}_{j}"] for j in LEG_JOINTS] for side in ("right", "left")}
    kinds = {"jump_foot": [(e["time"], e["side"]) for e in events if e["event"] in ("foot_flat", "heel_off", "toe_off")],
             "jump_hind": [(e["time"], OTHER[e["side"]]) for e in events if e["event"] == "heel_strike"]}
    for key, boundaries in kinds.items():
        per_boundary = []
        for tb, side in boundaries:
            if t_lo - 1e-9 <= tb <= t_hi + 1e-9:
                j = rate_jump(deg[:, own_leg[side]], t, fps, tb)
                if not np.all(np.isnan(j)):
                    per_boundary.append((tb, float(np.nanmax(j))))
        for _, t0, t1 in cycles:
            inside = [j for tb, j in per_boundary if t0 - 1e-9 <= tb < t1 - 1e-9]
            if inside:
                vals[key].append(max(inside))
    # the same statistic at every frame away from the listed boundaries: kinks inside a subphase
    d = np.diff(leg_deg, axis=0) * fps
    inner = np.abs(d[2:] - d[:-2])             # rates over (k-1, k) and (k+1, k+2): centred on k + 1/2
    mid = (t[1:-2] + t[2:-1]) / 2
    near = np.zeros(len(mid), bool)
    for tb, _ in main + other:
        near |= np.abs(mid - tb) < 2.5 / fps
    keep = np.flatnonzero((~near) & (mid >= t_lo) & (mid <= t_hi))
    elsewhere = (0.0, "", "")
    if len(keep):
        k = keep[np.argmax(inner[keep].max(axis=1))]
        col = int(np.argmax(inner[k]))
        side = "right" if leg_names[col].startswith("r_") else "left"
        hs = np.array([e["time"] for e in events if e["side"] == side and e["event"] == "heel_strike"])
        prev, nxt = hs[hs <= mid[k]], hs[hs > mid[k]]
        where = (f"{100 * (mid[k] - prev[-1]) / (nxt[0] - prev[-1]):.1f} % of its cycle"
                 if len(prev) and len(nxt) else f"t = {mid[k]:.3f} s")
        elsewhere = (float(inner[k, col]), leg_names[col], where)
    # peak swing hip torque of each steady step
    # (summary.json's peak_swing_hip_torque_per_kg: results.swing_hip_torque_peak)
    torque_at = []
    for k in range(START_STEPS, len(steps)):
        torque, subphase, t = swing_hip_torque_peak(steps[k])
        if subphase:
            vals["hip_torque"].append(abs(torque) / mass)
            torque_at.append((torque, subphase, t - steps[k].plan.timings.t_ds))
    human = human_figures(walk, bm, START_STEPS)
    for key in ("knee_mid", "knee_to", "thigh_min", "hip_range", "ankle_df", "ankle_pf", "stance_jump", "limb_jump",
                "hip_surge", "hip_decel"):
        vals[key] = list(human.values[key])
    for var in GPS_VARIABLES:
        vals[f"gvs_{var}"] = [v for (side, name), v in human.gvs.items() if name == var]
    vals["gps"] = [human.gps]
    plan = steps[0].plan
    return {"values": vals, "human": human, "cycles": cycles, "worst": worst, "elsewhere": elsewhere, "torque_at": torque_at,
            "plan": {"sl": plan.constraints.step_length, "sf": 60.0 / plan.timings.t_step,
                     "t_cycle": plan.timings.t_cycle, "t_ds": plan.timings.t_ds}}


# ------------------------------------------------------------------------------------------
# the report

def stat(v):
    v = np.asarray(v, float)
    v = v[np.isfinite(v)]
    if len(v) == 0:
        return math.nan, math.nan
    return float(v.mean()), float(v.std(ddof=1)) if len(v) > 1 else 0.0


def cell(v, digits):
    m, s = stat(v)
    if math.isnan(m):
        return "n/a"
    return f"{m:.{digits}f} ± {s:.{digits}f}"


def verdict(fig: Figure, v) -> str:
    m, _ = stat(v)
    if math.isnan(m):
        return "n/a"
    eps = 0.5 * 10 ** -fig.digits      # as printed
    if m < fig.low - eps:
        return f"outside ({fig.low - m:.{fig.digits}f} below {fig.low:g})"
    if m > fig.high + eps:
        return f"outside ({m - fig.high:.{fig.digits}f} above {fig.high:g})"
    return "within"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("config", nargs="?", default=str(ROOT / "configs" / "natural_walk.yaml"))
    ap.add_argument("--steps", type=int, default=10, help="steps per walk (default 10; the first 2 are the start)")
    ap.add_argument("--fps", type=float, default=200.0, help="body frames per second (default 200)")
    args = ap.parse_args(argv)
    wall0 = time.perf_counter()
    base = yaml.safe_load(Path(args.config).read_text(encoding="utf-8"))
    results = {}
    for speed in SPEEDS_KMH:
        t0 = time.perf_counter()
        walk = klaw_ocp.simulate_walk(speed_config(base, speed, args.steps), raise_on_failure=False)
        t1 = time.perf_counter()
        if walk.status != "ok" and len(walk.steps) < START_STEPS + 3:
            results[speed] = {"error": f"walk {walk.status}: {walk.message}"}
            print(f"{speed:g} km/h: {results[speed]['error']}")
            continue
        try:
            r = measure(walk, args.fps)
        except Exception as exc:          # report, never fail: the body is work in progress
            results[speed] = {"error": f"{type(exc).__name__}: {exc}"}
            print(f"{speed:g} km/h: measuring failed: {results[speed]['error']}")
            continue
        r["status"], r["walk_s"], r["body_s"] = walk.status, t1 - t0, time.perf_counter() - t1
        r["steps"] = len(walk.steps)
        results[speed] = r
    body = base.get("body", {})
    print(f"\nHow human is the walk: {Path(args.config).name}, {body.get('height')} m, {body.get('mass')} kg; "
          f"{args.steps} steps per walk, body at {args.fps:g} fps; steady cycles only "
          f"(from step {START_STEPS}), mean ± sd over cycles, both legs")
    for speed, r in results.items():
        if "error" in r:
            continue
        p = r["plan"]
        sides = {s: sum(1 for c in r["cycles"] if c[0] == s) for s in ("right", "left")}
        print(f"  {speed:g} km/h: sl {p['sl']:.3f} m, {p['sf']:.1f} steps/min, cycle {p['t_cycle']:.3f} s, "
              f"double support {p['t_ds']:.3f} s; {r['steps']} steps ({r['status']}); cycles used: "
              f"{sides['right']} right + {sides['left']} left; walk {r['walk_s']:.2f} s + body {r['body_s']:.2f} s")
    ok = [s for s in SPEEDS_KMH if "error" not in results.get(s, {"error": 1})]
    w_label, w_unit, w_val, w_typ = 46, 7, 17, 12
    head = f"{'figure':<{w_label}} {'unit':<{w_unit}}" + "".join(f"{f'{s:g} km/h':>{w_val}}" for s in ok) + \
           f"  {'typical adult':<{w_typ}}"
    print("\n" + head)
    print("-" * len(head))
    sections = {"knee_lr": "knee", "thigh_hs": "thigh and hip", "ankle_df": "ankle",
                "pelvis_list": "pelvis", "arm_range": "arm", "foot_flat": "event timing (% of cycle)",
                "jump_main": "smoothness (largest rate jump of any leg angle)", "hip_surge": "the hip's surge",
                "hip_torque": "swing hip torque",
                "gvs_thigh": "sagittal gait profile against the normative curves (docs/human-gait.md)"}
    for fig in FIGURES:
        if fig.key in sections:
            print(f"[{sections[fig.key]}]")
        row = f"{fig.label:<{w_label}} {fig.unit:<{w_unit}}"
        for s in ok:
            v = results[s]["values"][fig.key]
            mark = "" if verdict(fig, v) in ("within", "n/a") else "*"
            row += f"{cell(v, fig.digits) + mark:>{w_val}}"
        row += f"  {fig.typical}{' (s)' if fig.speed_dependent else ''}"
        print(row)
    print("-" * len(head))
    print("* outside the typical band; (s) the typical value depends on speed (the band is for ~5 km/h)")
    for s in ok:
        r = results[s]
        print(f"  {s:g} km/h: worst jump at heel strikes/toe-offs {r['worst']['jump_main'][0]:.0f} deg/s "
              f"({r['worst']['jump_main'][1]}, {r['worst']['jump_main'][2]}); at other boundaries "
              f"{r['worst']['jump_other'][0]:.0f} deg/s ({r['worst']['jump_other'][1]}, {r['worst']['jump_other'][2]}); "
              f"inside the subphases {r['elsewhere'][0]:.0f} deg/s ({r['elsewhere'][1]}, {r['elsewhere'][2]})")
        h = r["human"]
        where = max(zip(h.values["stance_jump"], h.values["stance_jump_where"]), key=lambda x: x[0], default=None)
        if where:
            print(f"  {s:g} km/h: v* = {h.v_star:.3f}; largest stance-leg rate jump at 100 fps {where[0]:.0f} deg/s "
                  f"({where[1][0]}, {where[1][1]:.1f} % of its cycle)")
        (jump, (name, when)) = h.values["limb_jump"][0], h.values["limb_jump_where"][0]
        print(f"  {s:g} km/h: largest leg or arm rate jump at 100 fps, 45 ms or more after heel strikes, "
              f"{jump:.0f} deg/s ({name}, t = {when:.2f} s)")
        if r["torque_at"]:
            f, sub, dt = max(r["torque_at"], key=lambda x: abs(x[0]))
            print(f"  {s:g} km/h: peak swing hip torque {f:+.0f} N m in {sub}, {1e3 * dt:.0f} ms after toe-off")
    print("\nVerdicts")
    for fig in FIGURES:
        parts = [f"{s:g} km/h {verdict(fig, results[s]['values'][fig.key])}" for s in ok]
        print(f"  {fig.label.strip():<{w_label}} [{fig.typical} {fig.unit}]: " + "; ".join(parts))
    print(f"\nwall time {time.perf_counter() - wall0:.1f} s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
