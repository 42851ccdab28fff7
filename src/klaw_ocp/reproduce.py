"""The paper, reproduced: figures 8, 9 and 10, the acceleration of section 5, the two solver modes
compared, and the paper's numbers beside ours, into ``results/paper/`` (``klaw-ocp reproduce``).

- Figure 8: "motion of one leg for two complete walking sequences": 2 km/h for 4 cycles and
  5 km/h for 3 cycles, each starting and ending at rest (configs/start_stop_2kmh.yaml,
  start_stop_5kmh.yaml): the strobe of one leg and the hip height.
- Figure 9: "pelvic list at toe-off. Left: natural pelvic list, right: accentuated pelvic list":
  the natural walk (8 steps) with pelvic_list 5 and 12 deg, the body in the frontal plane at a
  steady toe-off, and the swing hip torque F_theta3, which the lower swing hip changes (§2.4).
- Figure 10: "heel-strike for 3 walking sequences at v = 5 km/h": natural, short (sl = 0.50 m)
  and long (sl = 1.05 m) steps (natural_walk, short_steps, long_steps): the posture at a steady
  heel strike, side by side, with sl and sf beside the paper's.
- Section 5: "accelerations and decelerations … with a granularity of one step" (accelerate).
- Section 4.1: the natural walk in both solver modes; iterations per subphase beside the paper's
  "between 6 and 10"; the CPU time of the 12 s walk beside 37.3 s on a SUN3-50.

Everything is regenerated from the shipped configs; ``README.md`` sets the numbers side by side and
``numbers.json`` holds them for a program. Only small files are written (PNGs, JSON, Markdown, the
comparison CSV); the walks' own sample tables stay out.
"""
from __future__ import annotations

import json
import math
import platform
import time
from pathlib import Path

import numpy as np

from . import choices
from .compare import SUBPHASES
from .errors import ConfigError, ConvergenceError, out_of_range

#: what each part of the reproduction walks: key -> config file name in the configs folder
CONFIGS = {"fig8_2kmh": "start_stop_2kmh.yaml", "fig8_5kmh": "start_stop_5kmh.yaml",
           "natural": "natural_walk.yaml", "short": "short_steps.yaml", "long": "long_steps.yaml",
           "accelerate": "accelerate.yaml"}
#: the paper's own numbers (section 3 and fig. 10's caption, section 4.1, section 5)
PAPER = {"natural": {"sl_m": 0.77, "sf_spm": 107.5}, "short": {"sl_m": 0.50, "sf_spm": 166.7},
         "long": {"sl_m": 1.05, "sf_spm": 79.4}, "iterations": (6, 10), "cpu_s_12s_walk": 37.3,
         "cpu_machine": "SUN3-50 with floating point processor"}
#: figure 9: the natural walk, short, with a natural and an accentuated pelvic list (deg), the step
#: drawn at its toe-off and the body's frames per second (the posture is interpolated between them)
FIG9 = {"lists": {"natural": 5.0, "accentuated": 12.0}, "steps": 8, "step": 4, "fps": 240.0}
FIG9_FILE = "figure9_pelvic_list.png"


def check_configs(configs_dir) -> dict[str, Path]:
    """The config file of every part, checked (validated, nothing solved) before any walk."""
    from .config import load_config
    folder = Path(configs_dir)
    paths = {key: folder / name for key, name in CONFIGS.items()}
    missing = [str(p) for p in paths.values() if not p.is_file()]
    if missing:
        raise ConfigError(out_of_range("--configs", str(folder), f"a folder with {', '.join(CONFIGS.values())} "
                                       f"(missing {', '.join(missing)})"))
    for path in paths.values():
        load_config(path)
    return paths


def _walk(path: Path, method: str = choices.MULTIPLE_SHOOTING, progress: bool = False):
    """One walk and its CPU and wall time; a walk that does not converge stops the reproduction
    (its message names step, subphase and residual)."""
    from .result_files import RunData
    from .walk import simulate_walk
    cpu0, wall0 = time.process_time(), time.perf_counter()
    try:
        walk = simulate_walk(path, method=method, progress=progress)
    except ConvergenceError as exc:
        raise exc.within(f"{path.name} ({method})") from None
    run = RunData.from_walk(walk)
    run.extra.update(cpu_s=time.process_time() - cpu0, wall_s=time.perf_counter() - wall0, config=path.name)
    return run


def _fig9_walk(path: Path, list_deg: float, progress: bool = False):
    """Figure 9's walk: ``path``'s config, FIG9's steps, ``pelvic_list`` = ``list_deg``; its RunData's
    ``extra["fig9"]``: the swing hip's lowest point below the stance hip in FIG9's step's swing."""
    from .config_paths import set_path
    from .config_yaml import read_yaml_file
    from .result_files import RunData
    from .walk import simulate_walk
    config = read_yaml_file(path)
    for key, value in (("name", f"{config.get('name', path.stem)}_list{list_deg:g}"), ("walk.steps", FIG9["steps"]),
                       ("attributes.pelvic_list", list_deg), ("output.fps", FIG9["fps"]),
                       ("output.animation", False)):
        set_path(config, key, value)
    try:
        walk = simulate_walk(config, progress=progress)
    except ConvergenceError as exc:
        raise exc.within(f"{path.name} (pelvic_list {list_deg:g})") from None
    step, t = walk.steps[FIG9["step"]], walk.steps[FIG9["step"]].plan.timings
    tau = np.linspace(t.t_ds, t.t_step, 401)                       # toe-off to heel strike, step time
    dy = step.pelvis.swing_hip_offset(tau)[0][1]                   # the pelvis the swing was solved with
    run = RunData.from_walk(walk)
    run.extra["fig9"] = {"pelvic_list_deg": list_deg, "swing_hip_low_m": float(dy.min()),
                         "swing_hip_low_at_s": float(tau[np.argmin(dy)] - t.t_ds)}
    return run


def solve_all(paths: dict[str, Path], progress: bool = False) -> dict:
    """Every walk of the reproduction: key -> RunData; the natural walk in both modes, and with
    figure 9's two pelvic lists (``fig9_natural``, ``fig9_accentuated``)."""
    runs = {key: _walk(path, progress=progress) for key, path in paths.items()}
    runs["natural_ps"] = _walk(paths["natural"], choices.PLAIN_SHOOTING, progress)
    return {**runs, **fig9_runs(paths["natural"], progress)}


def fig9_runs(natural: Path, progress: bool = False) -> dict:
    """Figure 9's walks of the config ``natural``: ``fig9_<key>`` -> RunData for each of FIG9's lists."""
    return {f"fig9_{key}": _fig9_walk(natural, list_deg, progress) for key, list_deg in FIG9["lists"].items()}


def fig9_file(runs: dict) -> tuple[str, bytes]:
    """Figure 9 as (file name, PNG) from :func:`fig9_runs`' walks."""
    from .figures.paper_figures import fig9_figure
    from .figures.plot_style import png_bytes
    walks = [runs[f"fig9_{key}"] for key in FIG9["lists"]]
    return FIG9_FILE, png_bytes(fig9_figure(walks, FIG9["step"], list(FIG9["lists"])))


def fig9_numbers(runs: dict) -> dict:
    """Figure 9's numbers per walk: the list, the swing hip's lowest point, the peak swing hip
    torque (the largest |F_theta3| over the swing, signed) and the swings' torque parameters."""
    from .figures.paper_figures import swing_hip_torque
    k, out = FIG9["step"], {}
    for key in FIG9["lists"]:
        run = runs[f"fig9_{key}"]
        t, f, sub = swing_hip_torque(run, k)
        i = int(np.nanargmax(np.abs(f)))
        subphases = {s["name"]: s for s in run.steps[k]["subphases"]}
        out[key] = {**run.extra["fig9"], "step": k, "toe_off_s": run.steps[k]["t_start_s"] + run.steps[k]["t_ds_s"],
                    "peak_F_theta3_Nm": float(f[i]), "peak_at_s": float(t[i]), "peak_subphase": str(sub[i]),
                    "parameters": {name: {p: {"value": v, "unit": subphases[name]["units"].get(p, "")}
                                          for p, v in subphases[name]["parameters"].items()}
                                   for name in ("swing1", "swing2", "swing3")}}
    nat, acc = out["natural"]["peak_F_theta3_Nm"], out["accentuated"]["peak_F_theta3_Nm"]
    # in magnitude: the peaks may fall in different subphases with opposite signs (the swing1
    # flexion torque of one walk, the swing2 hold of the other)
    out["peak_change_Nm"] = abs(acc) - abs(nat)
    out["peak_change_pct"] = 100 * (abs(acc) - abs(nat)) / abs(nat)
    return out


def _steady(run) -> dict:
    """A step from the middle of a walk (its timings and heel-strike numbers stand for the walk)."""
    return run.steps[len(run.steps) // 2]


def hip_excursions(run) -> list[float]:
    """Peak-to-trough height of the hip within each step (m)."""
    t, y = run.table["t"], run.table["hip_y"]
    out = []
    for step in run.steps:
        mask = (t >= step["t_start_s"]) & (t <= step["t_start_s"] + step["t_step_s"])
        out.append(float(y[mask].max() - y[mask].min()) if mask.any() else float("nan"))
    return out


def iterations(run) -> dict:
    """Iterations per subphase over the walk: min, median, max, mean."""
    out = {}
    for name in SUBPHASES:
        its = [s["iterations"] for step in run.steps for s in step["subphases"] if s["name"] == name]
        if its:
            out[name] = {"min": int(min(its)), "median": float(np.median(its)), "max": int(max(its)),
                         "mean": float(np.mean(its))}
    return out


def numbers(runs: dict) -> dict:
    """Everything README.md sets beside the paper, as plain JSON-ready values."""
    fig10 = {}
    for key in ("natural", "short", "long"):
        step = _steady(runs[key])
        fig10[key] = {"sl_m": step["step_length_m"], "sf_spm": step["step_frequency_spm"],
                      "paper": PAPER[key], "theta1_rad": step["theta1_rad"], "theta3_rad": step["theta3_rad"],
                      "w_m": step["w_m"]}
    nat = _steady(runs["natural"])
    timing_keys = ("t_step_s", "t_ds_s", "t_stance_s", "t_swing_s", "t_swing1_end_s", "t_swing2_end_s",
                   "t_theta1_off_s")
    excursions = {key: hip_excursions(runs[key]) for key in ("natural", "short", "long", "fig8_2kmh", "fig8_5kmh")}
    modes = {}
    for key, method in (("natural", choices.MULTIPLE_SHOOTING), ("natural_ps", choices.PLAIN_SHOOTING)):
        run = runs[key]
        modes[method] = {"cpu_s": run.extra["cpu_s"], "wall_s": run.extra["wall_s"],
                         "solve_s": run.summary["wall_s"], "simulated_s": run.summary["simulated_s"],
                         "iterations": iterations(run)}
    acc = runs["accelerate"]
    return {
        "fig10": fig10,
        "fig9": fig9_numbers(runs),
        "timings_natural": {k: nat[k] for k in timing_keys},
        "hip_excursion_m": {k: {"steady": v[len(v) // 2], "min": min(v), "max": max(v)} for k, v in excursions.items()},
        "modes": modes,
        "accelerate": [{"step": s["index"], "speed_kmh": s["speed_kmh"], "sl_m": s["step_length_m"],
                        "sf_spm": s["step_frequency_spm"], "t_step_s": s["t_step_s"]} for s in acc.steps],
        "fig8": {k: {"steps": len(runs[k].steps), "duration_s": runs[k].duration} for k in ("fig8_2kmh", "fig8_5kmh")},
        "paper": {"iterations": list(PAPER["iterations"]), "cpu_s_12s_walk": PAPER["cpu_s_12s_walk"],
                  "cpu_machine": PAPER["cpu_machine"]},
        "machine": {"python": platform.python_version(), "processor": platform.processor() or platform.machine()},
    }


def _f(value, digits=3) -> str:
    return "–" if value is None or (isinstance(value, float) and not math.isfinite(value)) else f"{value:.{digits}f}"


def fig9_readme(f9: dict) -> list[str]:
    """README.md's section of figure 9: the two walks' swing hip, peak hip torque and parameters."""
    nat, acc = f9["natural"], f9["accentuated"]
    lines = [
        "## Figure 9: pelvic list at toe-off",
        "",
        f"![figure 9]({FIG9_FILE})",
        "",
        f"The natural walk ({FIG9['steps']} steps at 5 km/h) with a natural and an accentuated pelvic list, "
        f"the rest default; step {nat['step']} at its toe-off, and the swing hip torque F_θ3 over that step's swing. "
        "The list lowers the swing leg's hip about the stance hip (§4.2); the paper: it \"might 'force' the dynamic "
        "leg to increase its hip torque to avoid stubbing its toe\" (§2.4).",
        "",
        "| walk | pelvic_list (deg) | swing hip's lowest point below the stance hip (m) | at (s after toe-off) | "
        "peak F_θ3 over the swing (N m) | at (s after toe-off) | in |",
        "|---|---|---|---|---|---|---|",
    ]
    walks = (("natural", nat), ("accentuated", acc))
    lines += [f"| {key} | {r['pelvic_list_deg']:g} | {_f(-r['swing_hip_low_m'], 4)} | {_f(r['swing_hip_low_at_s'])} | "
              f"{_f(r['peak_F_theta3_Nm'], 1)} | {_f(r['peak_at_s'])} | {r['peak_subphase']} |" for key, r in walks]
    names = [(sub, p, nat["parameters"][sub][p]["unit"]) for sub in ("swing1", "swing2", "swing3")
             for p in nat["parameters"][sub]]
    lines += ["", f"The accentuated list changes the peak swing hip torque's magnitude by "
              f"{f9['peak_change_Nm']:+.1f} N m ({f9['peak_change_pct']:+.1f} %). The swings' torque parameters (§4.3) of step "
              f"{nat['step']}:", "", "| subphase | parameter | natural | accentuated |", "|---|---|---|---|"]
    lines += [f"| {sub} | {p} ({unit}) | {_f(nat['parameters'][sub][p]['value'], 3)} | "
              f"{_f(acc['parameters'][sub][p]['value'], 3)} |" for sub, p, unit in names]
    lifted = [key for key, r in walks if r["parameters"]["swing2"]["hip_actuator"]["value"]]
    lines += ["", f"swing2's hip_actuator is its recovery (§4.3), which lifts the foot clear of the ground: it acted "
              f"in {' and '.join(lifted) or 'neither walk'}.", ""]
    return lines


def readme(n: dict, comparison_text: str) -> str:
    """``results/paper/README.md``: each picture with our numbers beside the paper's."""
    f10, tm, ex, modes = n["fig10"], n["timings_natural"], n["hip_excursion_m"], n["modes"]
    lines = [
        "# The paper, reproduced",
        "",
        "Bruderlin & Calvert, *Goal-Directed, Dynamic Animation of Human Walking* (SIGGRAPH 1989), "
        "regenerated by `klaw-ocp reproduce` from the shipped configs (configs/). Every walk is a 1.8 m, "
        "80 kg body; multiple shooting unless said otherwise. `numbers.json` holds every number below.",
        "",
        "## Figure 10: heel strike of three walks at 5 km/h",
        "",
        "![figure 10](fig10.png)",
        "",
        "| walk | sl ours (m) | sl paper (m) | sf ours (steps/min) | sf paper (steps/min) | θ1 at heel strike (rad) | θ3 (rad) | w (m) |",
        "|---|---|---|---|---|---|---|---|",
    ]
    for key, label in (("natural", "natural (v only)"), ("short", "short (sl = 0.50 m)"), ("long", "long (sl = 1.05 m)")):
        r = f10[key]
        lines.append(f"| {label} | {_f(r['sl_m'])} | {r['paper']['sl_m']:.2f} | {_f(r['sf_spm'], 1)} | "
                     f"{r['paper']['sf_spm']:.1f} | {_f(r['theta1_rad'])} | {_f(r['theta3_rad'])} | {_f(r['w_m'])} |")
    lines += [
        "",
        "The paper prints 107.5 steps/min for the natural walk; eq. 1 gives 107.58 (ERRATA 9: truncated).",
        "",
        "## Figure 8: one leg, starting and stopping",
        "",
        "![figure 8](fig8.png)",
        "",
        f"2 km/h for 4 cycles: {n['fig8']['fig8_2kmh']['steps']} steps ({n['fig8']['fig8_2kmh']['duration_s']:.2f} s, "
        f"the last one closing the walk at rest); 5 km/h for 3 cycles: {n['fig8']['fig8_5kmh']['steps']} steps "
        f"({n['fig8']['fig8_5kmh']['duration_s']:.2f} s). Each starts standing on both feet and ends standing.",
        "",
    ]
    lines += fig9_readme(n["fig9"])
    lines += [
        "## Phase timings of the natural walk (eq. 2, §4.2, §4.3)",
        "",
        "| quantity | ours (s) | the paper's rule |",
        "|---|---|---|",
        f"| t_step | {_f(tm['t_step_s'], 4)} | 60 / sf |",
        f"| t_ds | {_f(tm['t_ds_s'], 4)} | (−0.16 sf + 29.08) % of t_cycle |",
        f"| t_stance | {_f(tm['t_stance_s'], 4)} | t_step + t_ds |",
        f"| t_swing | {_f(tm['t_swing_s'], 4)} | t_step − t_ds |",
        f"| end of swing1 | {_f(tm['t_swing1_end_s'], 4)} | 50 % of t_swing |",
        f"| end of swing2 | {_f(tm['t_swing2_end_s'], 4)} | 85 % of t_swing |",
        f"| F_θ1 off | {_f(tm['t_theta1_off_s'], 4)} | 0.4 t_step |",
        "",
        "The gait diagram of the natural walk: ![gait diagram](natural_gait_diagram.png)",
        "",
        "## Hip height: the vertical sinusoid (§4.2)",
        "",
        "![hip height](natural_hip_height.png)",
        "",
        "The paper asks that \"the hip of the stance model prescribes a vertical sinusoidal curve typical in "
        "human walking\" and never drops below its height at heel strike; it gives no number. Our hip's "
        "peak-to-trough excursion per step (m; Inman's adults: about 0.04–0.05 m at a natural pace):",
        "",
        "| walk | steady step | smallest | largest |",
        "|---|---|---|---|",
    ]
    for key, label in (("natural", "natural 5 km/h"), ("short", "short steps"), ("long", "long steps"),
                       ("fig8_2kmh", "2 km/h start-stop"), ("fig8_5kmh", "5 km/h start-stop")):
        e = ex[key]
        lines.append(f"| {label} | {_f(e['steady'], 4)} | {_f(e['min'], 4)} | {_f(e['max'], 4)} |")
    lines += [
        "",
        "## Acceleration: 2 → 5 → 2 km/h, a granularity of one step (§5)",
        "",
        "![acceleration](acceleration.png)",
        "",
        "| step | v (km/h) | sl (m) | sf (steps/min) | t_step (s) |",
        "|---|---|---|---|---|",
    ]
    lines += [f"| {a['step']} | {_f(a['speed_kmh'], 2)} | {_f(a['sl_m'])} | {_f(a['sf_spm'], 1)} | {_f(a['t_step_s'])} |"
              for a in n["accelerate"]]
    lo, hi = n["paper"]["iterations"]
    lines += [
        "",
        "## The two solver modes on the natural walk (§4.1)",
        "",
        "![comparison](comparison.png)",
        "",
        "```",
        comparison_text.rstrip(),
        "```",
        "",
        f"Iterations per subphase (the paper: \"usually … between {lo} and {hi}\", bisection then secant):",
        "",
        "| subphase | multiple shooting min / median / max | plain shooting min / median / max |",
        "|---|---|---|",
    ]
    for name in SUBPHASES:
        cells = []
        for method in (choices.MULTIPLE_SHOOTING, choices.PLAIN_SHOOTING):
            it = modes[method]["iterations"].get(name)
            cells.append(f"{it['min']} / {it['median']:g} / {it['max']}" if it else "–")
        lines.append(f"| {name} | {cells[0]} | {cells[1]} |")
    ms, ps = modes[choices.MULTIPLE_SHOOTING], modes[choices.PLAIN_SHOOTING]
    lines += [
        "",
        "Multiple shooting's iterations are Newton steps on the whole subphase; plain shooting's count "
        "the shots of its bisection and secant sweeps, as the paper's do.",
        "",
        f"CPU time of the 12 s natural walk (the paper: {n['paper']['cpu_s_12s_walk']} s on a {n['paper']['cpu_machine']}):",
        "",
        "| mode | CPU (s) | wall (s) | of which solving (s) | real-time factor |",
        "|---|---|---|---|---|",
        f"| multiple shooting | {_f(ms['cpu_s'], 2)} | {_f(ms['wall_s'], 2)} | {_f(ms['solve_s'], 2)} | "
        f"{ms['simulated_s'] / ms['wall_s']:.0f}× |",
        f"| plain shooting | {_f(ps['cpu_s'], 2)} | {_f(ps['wall_s'], 2)} | {_f(ps['solve_s'], 2)} | "
        f"{ps['simulated_s'] / ps['wall_s']:.0f}× |",
        "",
        f"Measured on this run's machine (Python {n['machine']['python']}, {n['machine']['processor']}), solver "
        "kernels already compiled; the times change from machine to machine and run to run. The paper's 37.3 s "
        "was 3× slower than real time; docs/performance.md has the benchmark.",
        "",
        "Regenerate everything with `klaw-ocp reproduce` (a few seconds).",
        "",
    ]
    return "\n".join(lines)


def reproduce(configs_dir="configs", out_dir="results/paper", progress: bool = False) -> dict:
    """Solve every walk, draw every figure and write ``out_dir``; returns name -> path."""
    from .compare import comparison_csv, comparison_rows, comparison_stats, comparison_table
    from .figures.compare_plot import comparison_figure
    from .figures.paper_figures import acceleration_figure, fig8_figure, fig10_figure
    from .figures.plot_style import png_bytes
    from .figures.registry import PLOTS
    from .result_files.atomic import atomic_write_text, write_rendered
    from .result_files.registry import COMPARISON_CSV, COMPARISON_PNG, NUMBERS_JSON, PAPER_README, load

    paths = check_configs(configs_dir)
    runs = solve_all(paths, progress)
    modes = [runs["natural"], runs["natural_ps"]]
    comparison = comparison_table(comparison_stats(modes))
    n = numbers(runs)
    files = {
        "fig8": ("fig8.png", png_bytes(fig8_figure(runs["fig8_2kmh"], runs["fig8_5kmh"]))),
        "fig10": ("fig10.png", png_bytes(fig10_figure([runs["natural"], runs["short"], runs["long"]], PAPER))),
        "fig9": fig9_file(runs),
        "acceleration": ("acceleration.png", png_bytes(acceleration_figure(runs["accelerate"]))),
        "comparison": (COMPARISON_PNG, png_bytes(comparison_figure(modes))),
        "comparison_csv": (COMPARISON_CSV, comparison_csv(comparison_rows(modes)).encode("utf-8")),
        "numbers": (NUMBERS_JSON, (json.dumps(n, indent=2, allow_nan=False) + "\n").encode("utf-8")),
    }
    for name in ("hip_height", "gait_diagram"):
        plot = PLOTS[name]
        files[f"natural_{name}"] = (f"natural_{plot.file}", png_bytes(load(plot.figure)(runs["natural"])))
    written = write_rendered(files, out_dir)
    written["readme"] = Path(out_dir) / PAPER_README
    atomic_write_text(written["readme"], readme(n, comparison))
    return written
