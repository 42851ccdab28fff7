"""Benchmark: the natural walk in every solver mode, warm and as a cold command, with the targets.

    python benchmarks/bench_walk.py [CONFIG] [--repeats 5] [--json] [--all-cores]

For each mode (multiple shooting with the paper's monitored stance, plain shooting, multiple
shooting with the tracking stance) it runs the walk once to build or load the solvers, then
``--repeats`` more times, and reports the medians of:

- the solver build time: how much longer the first walk in the process took than the others
  (CasADi functions, compiled kernels loaded from the disk cache or compiled, IPOPT instances);
- each subphase's solve time and iterations (median over the walk's steps);
- the dynamics (``simulate_walk``), the full pipeline (the dynamics plus every result file
  rendered in memory) and the writing of the files;
- the real-time factor (walked seconds per wall second of the full pipeline).

It times the kinematics on their own line: the body's 56 angles at 30 fps (``body_motion`` of
the multiple-shooting walk), and the walk with its angles (the dynamics plus those) as a
real-time factor, issue #22's target.

It times the seven plots of a run (``klaw_ocp.figures.plots.render_plots`` of the multiple-shooting
walk) on their own line: the first rendering in the process (it imports matplotlib) and the median
of the others; and, apart from the walk, its ``walk.gif`` (``klaw_ocp.figures.animation``, docs/gif.md:
rendered and written once, after the plots); and the step-by-step writing of ``klaw-ocp run``
(``klaw_ocp.result_files.run_writer``: ms a step, and its cost beyond a one-shot write). Then it runs ``klaw-ocp run CONFIG --no-plots
--no-animation`` twice as whole processes with an empty kernel cache (the first compiles the
kernels, the second loads them) and ``klaw-ocp run CONFIG`` with its plots and walk.gif once
more (``cold_cli_plots_s``; on every processor the benchmark was given, since those are drawn on
every core), and reports their wall time and peak RSS.
The process is pinned to one CPU unless ``--all-cores``. With ``--json`` the last line is one
JSON object (``realtime_factor``, ``realtime_factor_plain_shooting``, ``realtime_factor_tracking``,
``ms_over_ps_time_ratio``, ``cold_cli_s``, ``cold_cli_plots_s``, ``first_cold_cli_s``,
``plots_s``, ``animation_s``, ``animation_mb``, ``peak_rss_mb``, ...).
Timings are measured here and in docs/performance.md, never asserted in tests.
"""
from __future__ import annotations

import argparse
import json
import os
import resource
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from dataclasses import replace

from klaw_ocp.body_motion import body_motion
from klaw_ocp.config import load_config
from klaw_ocp.result_files import render_walk, write_rendered
from klaw_ocp.walk import simulate_walk, walk_spec
from reference_machine import REFERENCE_STANCE_SOLVE_MS, slower_than_reference

MODES = (("multiple-shooting", "monitored"), ("plain-shooting", "monitored"), ("multiple-shooting", "tracking"))
TARGETS = (("realtime_factor", ">=", 50.0), ("ms_over_ps_time_ratio", "<=", 1.0),
           ("realtime_factor_tracking", ">=", 10.0), ("cold_cli_s", "<=", 5.0), ("cold_cli_plots_s", "<=", 3.0),
           ("peak_rss_mb", "<=", 300.0), ("realtime_factor_walk_and_angles", ">=", 100.0))


def _mode(config, method: str, stance: str, repeats: int) -> dict:
    spec = replace(walk_spec(config, method), stance=stance)
    t0 = time.perf_counter()
    first = simulate_walk(spec)   # builds or loads every solver of this mode
    first_s = time.perf_counter() - t0
    dynamics, pipeline, writing, walk = [], [], [], first
    for _ in range(repeats):
        t0 = time.perf_counter()
        walk = simulate_walk(spec)
        t1 = time.perf_counter()
        files = render_walk(walk)
        t2 = time.perf_counter()
        with tempfile.TemporaryDirectory() as out:
            write_rendered(files, out)
        t3 = time.perf_counter()
        dynamics.append(t1 - t0); pipeline.append(t2 - t0); writing.append(t3 - t2)
    per_subphase = {}
    for name in ("stance", "swing1", "swing2", "swing3"):
        subs = [step.subphase(name) for step in walk.steps]
        per_subphase[name] = {"median_ms": 1e3 * statistics.median(s.wall_s for s in subs),
                              "median_iterations": statistics.median(s.iterations for s in subs)}
    pipe = statistics.median(pipeline)
    # the one-off cost of the first walk in this process: CasADi functions, kernels from the disk
    # cache (or compiled, the first time on a machine), IPOPT instances
    build = max(0.0, first_s - statistics.median(dynamics))
    return {"mode": f"{method}/{stance}", "steps": len(walk.steps), "walked_s": walk.duration, "build_s": build,
            "dynamics_s": statistics.median(dynamics), "pipeline_s": pipe, "write_s": statistics.median(writing),
            "realtime_factor": walk.duration / pipe, "subphases": per_subphase}


def _step_writing(config, repeats: int) -> dict:
    """``klaw-ocp run``'s writing as the walk goes (klaw_ocp.result_files.run_writer, multiple shooting):
    the medians of the per-step writing (ms a step), of the rest written at the end (ms), of a
    one-shot render and write of the same walk (ms, the writing before issue #24), and what the
    step-by-step writing costs beyond it (ms a step)."""
    from klaw_ocp.result_files.run_writer import RunWriter
    spec = walk_spec(config, "multiple-shooting")
    per_step, finish, once, steps = [], [], [], 1
    for _ in range(repeats):
        with tempfile.TemporaryDirectory() as out:
            writer = RunWriter(out, "resolved: true\n")
            walk = simulate_walk(spec, on_step=writer.step)
            t0 = time.perf_counter()
            writer.finish(walk)
            finish.append(time.perf_counter() - t0)
            per_step.append(writer.step_s)
            steps = len(walk.steps)
        with tempfile.TemporaryDirectory() as out:
            t0 = time.perf_counter()
            write_rendered(render_walk(walk, 30), out)
            once.append(time.perf_counter() - t0)
    step_s, finish_s, once_s = (statistics.median(v) for v in (per_step, finish, once))
    return {"step_ms": 1e3 * step_s / steps, "finish_ms": 1e3 * finish_s, "once_ms": 1e3 * once_s,
            "extra_ms_per_step": 1e3 * (step_s + finish_s - once_s) / steps}


def _median_s(fn, repeats: int) -> float:
    """The median of ``repeats`` timed calls of ``fn`` (s)."""
    times = []
    for _ in range(repeats):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return statistics.median(times)


def _plots(walk, repeats: int) -> tuple[float, float]:
    """The seven plots of ``walk`` rendered in memory: the first time (with matplotlib's import) and
    the median of ``repeats`` more (s)."""
    from klaw_ocp.result_files import RunData
    run = RunData.from_walk(walk)
    t0 = time.perf_counter()
    from klaw_ocp.figures.plots import render_plots
    render_plots(run)
    first = time.perf_counter() - t0
    return first, _median_s(lambda: render_plots(run), repeats)


def _animation(walk) -> tuple[float, float]:
    """walk.gif of ``walk`` rendered and written once (after the plots: matplotlib is loaded):
    its time (s) and size (MB)."""
    from klaw_ocp.result_files import RunData
    from klaw_ocp.figures.animation import GIF_FILE, write_animation
    run = RunData.from_walk(walk)
    with tempfile.TemporaryDirectory() as out:
        t0 = time.perf_counter()
        path = write_animation(run, os.path.join(out, GIF_FILE))
        seconds = time.perf_counter() - t0
        return seconds, os.path.getsize(path) / 1e6


#: measures a command's peak RSS from a small process: a child forked from this benchmark (200 MB
#: of CasADi and compiled kernels) would count the fork's pages before exec as its own
_RSS_PROBE = ("import resource, subprocess, sys; code = subprocess.call(sys.argv[1:], stdout=subprocess.DEVNULL); "
              "print(resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss); sys.exit(code)")


def _cold_cli(config_path: str, cache: str, plots: bool = False, cpus=None) -> tuple[float, float]:
    """Wall time (s) and peak RSS (MB) of one ``klaw-ocp run`` process: without ``plots``, with
    neither plots nor walk.gif; with ``plots``, with both (as a user runs it), on ``cpus`` (the
    processors this benchmark was given: the plots and walk.gif are drawn on every core,
    klaw_ocp.figures.render_pool) rather than on the one this process is pinned to."""
    env = dict(os.environ, KLAW_OCP_CACHE_DIR=cache)
    with tempfile.TemporaryDirectory() as out:
        command = shutil.which("klaw-ocp") or "klaw-ocp"   # the command users type, as a whole process
        flags = [] if plots else ["--no-plots", "--no-animation"]
        unpinned = (lambda: os.sched_setaffinity(0, cpus)) if cpus else None
        probe = subprocess.Popen([sys.executable, "-c", _RSS_PROBE, command, "run", config_path, "--out", out,
                                  "--quiet", *flags], env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                 preexec_fn=unpinned)
        t0 = time.perf_counter()
        stdout, stderr = probe.communicate()
        wall = time.perf_counter() - t0   # includes the probe's own start (~20 ms)
    if probe.returncode != 0:
        raise SystemExit(f"klaw-ocp run failed: {stderr.decode()[-500:]}")
    return wall, int(stdout.split()[-1]) / 1024.0


def _kinematics(walk, fps: float, dynamics_s: float, repeats: int) -> dict:
    """The body's 56 angles at the config's ``output.fps`` on their own (``body_motion``, the
    kinematics: virtual legs, swing feet, pelvis, upper body; median of ``repeats``), and the walk
    with its angles (issue #22: the dynamics' median plus this) as a real-time factor."""
    body_motion(walk, fps)
    kinematics = _median_s(lambda: body_motion(walk, fps), repeats)
    return {"fps": fps, "kinematics_s": kinematics, "walk_and_angles_s": dynamics_s + kinematics,
            "realtime_factor_walk_and_angles": walk.duration / (dynamics_s + kinematics)}


def _table(rows: list, cli: list, plots: tuple[float, float], animation: tuple[float, float], steps: dict,
           kinematics: dict) -> str:
    lines = [f"{'mode':34s} {'steps':>5s} {'build s':>8s} {'dynamics s':>10s} {'pipeline s':>10s} "
             f"{'write s':>8s} {'x real time':>11s}"]
    for r in rows:
        lines.append(f"{r['mode']:34s} {r['steps']:5d} {r['build_s']:8.3f} {r['dynamics_s']:10.4f} "
                     f"{r['pipeline_s']:10.4f} {r['write_s']:8.4f} {r['realtime_factor']:11.1f}")
    lines.append("")
    lines.append(f"{'median solve, ms (iterations)':34s} " + " ".join(f"{n:>14s}" for n in ("stance", "swing1", "swing2", "swing3")))
    for r in rows:
        cells = [f"{v['median_ms']:7.2f} ({v['median_iterations']:g})" for v in r["subphases"].values()]
        lines.append(f"{r['mode']:34s} " + " ".join(f"{c:>14s}" for c in cells))
    lines.append("")
    lines.append(f"kinematics (the body's 56 angles at {kinematics['fps']:g} fps, multiple-shooting walk): "
                 f"{1e3 * kinematics['kinematics_s']:.1f} ms; the walk with its angles "
                 f"{kinematics['walk_and_angles_s']:.4f} s, {kinematics['realtime_factor_walk_and_angles']:.1f}x real time")
    lines.append(f"plots (7 PNGs of the multiple-shooting walk, one process): first {plots[0]:.2f} s (imports matplotlib), "
                 f"then {plots[1]:.2f} s")
    lines.append(f"animation (walk.gif of the natural walk): {animation[0]:.2f} s, {animation[1]:.2f} MB")
    lines.append(f"step-by-step writing (multiple shooting): {steps['step_ms']:.2f} ms a step, then "
                 f"{steps['finish_ms']:.0f} ms at the end; a one-shot write {steps['once_ms']:.0f} ms; "
                 f"{steps['extra_ms_per_step']:.2f} ms a step more")
    lines.append("")
    labels = ("--no-plots, first (compiles kernels)", "--no-plots, cached kernels", "plots + gif, cached kernels")
    for label, (wall, rss) in zip(labels, cli):
        lines.append(f"cold `klaw-ocp run`, {label:37s} {wall:6.2f} s, peak RSS {rss:6.1f} MB")
    return "\n".join(lines)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default="configs/natural_walk.yaml")
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--json", action="store_true", help="end with one line of JSON")
    parser.add_argument("--all-cores", action="store_true", help="do not pin the process to one CPU")
    args = parser.parse_args()
    cpus = os.sched_getaffinity(0) if hasattr(os, "sched_getaffinity") else None
    if not args.all_cores and cpus:
        os.sched_setaffinity(0, {sorted(cpus)[0]})
    config = load_config(args.config)
    rows = [_mode(config, method, stance, args.repeats) for method, stance in MODES]
    walk = simulate_walk(walk_spec(config, "multiple-shooting"))
    kinematics = _kinematics(walk, config.output.fps, rows[0]["dynamics_s"], args.repeats)
    plots = _plots(walk, args.repeats)
    animation = _animation(walk)
    steps = _step_writing(config, args.repeats)
    own_rss = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0
    with tempfile.TemporaryDirectory() as cache:
        cli = [_cold_cli(args.config, cache) for _ in range(2)] + [_cold_cli(args.config, cache, plots=True, cpus=cpus)]
    ms, ps, tracking = rows
    result = {
        "realtime_factor": ms["realtime_factor"],
        "realtime_factor_plain_shooting": ps["realtime_factor"],
        "realtime_factor_tracking": tracking["realtime_factor"],
        "ms_over_ps_time_ratio": ms["pipeline_s"] / ps["pipeline_s"],
        "cold_cli_s": cli[1][0], "first_cold_cli_s": cli[0][0], "cold_cli_plots_s": cli[2][0],
        "plots_first_s": plots[0], "plots_s": plots[1], "animation_s": animation[0], "animation_mb": animation[1],
        "step_write_ms": steps["step_ms"], "step_write_extra_ms": steps["extra_ms_per_step"],
        "peak_rss_mb": max(rss for _, rss in cli), "benchmark_process_rss_mb": own_rss,
        "walk_s": ms["walked_s"], "modes": rows, **kinematics,
        "machine": {"cpu_count": os.cpu_count(), "pinned_to_one_cpu": not args.all_cores, "python": sys.version.split()[0]},
    }
    print(_table(rows, cli, plots, animation, steps, kinematics))
    print(f"\nmultiple shooting / plain shooting time: {result['ms_over_ps_time_ratio']:.2f}; "
          f"benchmark process peak RSS {own_rss:.0f} MB")
    for key, op, bound in TARGETS:
        value = result[key]
        held = value >= bound if op == ">=" else value <= bound
        print(f"target {key} {op} {bound:g}: {value:.3g} {'holds' if held else 'MISSED'}")
    # the machine: an estimate of the figures on the reference machine, clearly not a measurement
    slower = slower_than_reference(ms["subphases"]["stance"]["median_ms"])
    result["machine"]["stance_solve_ms"] = ms["subphases"]["stance"]["median_ms"]
    result["machine"]["slower_than_reference"] = slower
    print(f"\nthis machine's median stance solve is {ms['subphases']['stance']['median_ms']:.2f} ms, "
          f"{slower:.2f}x the reference machine's {REFERENCE_STANCE_SOLVE_MS} ms (docs/performance.md); "
          f"scaled by that (an estimate, not measured): real-time factor ~{ms['realtime_factor'] * slower:.0f}x, "
          f"the walk with its angles ~{kinematics['realtime_factor_walk_and_angles'] * slower:.0f}x, "
          f"tracking ~{tracking['realtime_factor'] * slower:.0f}x, cold run with plots and gif "
          f"~{cli[2][0] / slower:.1f} s")
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
