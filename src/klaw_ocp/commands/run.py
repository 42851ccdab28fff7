"""``klaw-ocp run``, ``validate`` and ``plot``: one walk from a config file (section 2.4: high
level, then the low level step by step), its check without solving, and its plots redrawn from a
finished results folder.

``run`` writes into the results folder: ``summary.json``, ``dynamics.csv``, ``events.csv``,
``angles.csv`` (the body at ``output.fps`` frames per second, docs/body.md),
``config.resolved.yaml`` (the config with its ``--set``, ``--method``, ``--stance`` and ``--fps``
folded in and every default filled in: running it again gives the same ``dynamics.csv`` bytes)
and, unless ``--no-plots`` or ``output.plots: false``, the plots of :mod:`klaw_ocp.io.plots` in
``plots/``; with ``output.animation: true`` (the shipped configs) and without ``--no-animation``,
``walk.gif`` (:mod:`klaw_ocp.io.animation`, docs/gif.md), after the plots and independent of them.
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

from . import EXIT_NOT_CONVERGED, EXIT_OK, PROG
from ._common import add_set_option, check_output_dir, check_plots, load, resolved_header

RUN_HELP = "simulate a configured walk and write its result files and plots"
VALIDATE_HELP = "check a config and print its walk plan, solving nothing"
PLOT_HELP = "redraw the plots of a finished results folder, solving nothing"
RESOLVED_FILE = "config.resolved.yaml"
PLOTS_DIR = "plots"
GIF_FILE = "walk.gif"        # = klaw_ocp.io.animation.GIF_FILE (not imported here: it loads matplotlib)


def configure_run(p: argparse.ArgumentParser) -> None:
    p.description = ("Simulate the configured walk step by step and write summary.json, dynamics.csv, "
                     "events.csv, angles.csv (the body's 56 angles at every frame), config.resolved.yaml, "
                     "the plots (plots/*.png) and, with output.animation, walk.gif to --out (default "
                     "results/<name>/). A subphase that does not converge is reported on one line "
                     "(step, subphase, residual); the steps completed before it are still written, "
                     "and the exit code is 1.")
    p.epilog = ("example: klaw-ocp run configs/natural_walk.yaml --set walk.speed=4 "
                "--method plain-shooting --out /tmp/slow")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: output.dir or results/<name>/)")
    p.add_argument("--method", choices=("multiple-shooting", "plain-shooting"),
                   help="solver mode (default: the config's solver.method)")
    p.add_argument("--stance", choices=("monitored", "tracking"),
                   help="stance formulation: the paper's monitored pa, or pa optimised over the grid "
                        "to track the hip sinusoid (multiple shooting only; default: solver.stance)")
    p.add_argument("--fps", metavar="FPS",
                   help="frames per second of angles.csv, a number > 0 and <= 1000 (default: output.fps, 30)")
    add_set_option(p)
    p.add_argument("--no-plots", action="store_true", help="skip the plots (as output.plots: false)")
    p.add_argument("--no-animation", action="store_true",
                   help="skip walk.gif (as output.animation: false; the plots are not affected)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def handle_run(args: argparse.Namespace) -> int:
    config = load(args.config, args.sets, args.method, args.stance, args.fps)
    out = check_output_dir(args.out if args.out is not None else config.output_dir(),
                           "--out" if args.out is not None else "output.dir")
    check_plots(config, config.output.plots and not args.no_plots)
    from ..errors import ConvergenceError
    from ..walk import simulate_walk, walk_spec     # the solvers: only for a valid run
    failure = None
    try:
        walk = simulate_walk(walk_spec(config), progress=not args.quiet)
    except ConvergenceError as exc:
        walk, failure = exc.partial, exc
    header = resolved_header(args.config, args.sets, args.method, args.stance, args.fps)
    paths, times = write_run(walk, config.resolved_yaml(header), out, config.output.fps,
                             plots=config.output.plots and not args.no_plots,
                             animation=config.output.animation and not args.no_animation)
    if failure is not None:
        print(f"{PROG}: error: {failure}; {len(walk.steps)} completed step(s) written to {out}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    rtf = walk.duration / walk.wall_s if walk.wall_s else float("inf")
    n_plots = sum(path.parent.name == PLOTS_DIR for path in paths.values())
    plots = f"; {n_plots} plots in {times['plots']:.2f} s" if times["plots"] is not None else ""
    if times["animation"] is not None:
        plots += f"; {GIF_FILE} in {times['animation']:.2f} s"
    print(f"{walk.spec.name}: {len(walk.steps)} steps, {walk.duration:.2f} s of walking in {walk.wall_s:.2f} s "
          f"({rtf:.1f}x real time, {walk.spec.method}, {walk.spec.stance} stance){plots}; wrote {out}/")
    return EXIT_OK


def write_run(walk, resolved_yaml: str, out: Path, fps: float, plots: bool = True,
              animation: bool = False) -> tuple[dict, dict]:
    """Write a walk's result files (each atomically; the body's angles at ``fps``), with ``plots``
    its plots and with ``animation`` its walk.gif; returns the paths by name and the drawing times
    {"plots": s, "animation": s} (None for what was not drawn). Plots or a walk.gif left in ``out``
    by an earlier run and not drawn again are removed: they would show another walk."""
    from ..io import RunData, render_run, write_rendered
    run = RunData.from_walk(walk, fps=fps)
    files = render_run(run)
    files["resolved"] = (RESOLVED_FILE, resolved_yaml.encode("utf-8"))
    paths = write_rendered(files, out)
    times = {"plots": None, "animation": None}
    if plots and walk.steps:
        t0 = time.perf_counter()
        from ..io.plots import render_plots
        paths.update(write_rendered(render_plots(run), out / PLOTS_DIR))
        times["plots"] = time.perf_counter() - t0
    else:
        _remove_stale_plots(out / PLOTS_DIR)
    gif = None
    if animation and walk.steps:
        t0 = time.perf_counter()
        from ..io.animation import write_animation
        gif = write_animation(run, out / GIF_FILE)
        times["animation"] = time.perf_counter() - t0 if gif is not None else None
    if gif is None:
        (out / GIF_FILE).unlink(missing_ok=True)
    else:
        paths["animation"] = gif
    return paths, times


def _remove_stale_plots(folder: Path) -> None:
    # plots/ is ours (run and plot write it): every PNG in it was drawn from an earlier walk
    for png in folder.glob("*.png") if folder.is_dir() else ():
        png.unlink(missing_ok=True)


def configure_validate(p: argparse.ArgumentParser) -> None:
    p.description = ("Validate CONFIG (with its --set overrides) exactly as run does, and print the "
                     "resolved walk plan: every step's parameters (eq. 1), timings (eq. 2) and "
                     "heel-strike constraints (eq. 3). Nothing is solved, compiled or written. Exit "
                     "code 0 if the walk can be run, 2 with a one-line error otherwise.")
    p.epilog = "example: klaw-ocp validate configs/accelerate.yaml --set walk.steps=12"
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    add_set_option(p)


def handle_validate(args: argparse.Namespace) -> int:
    from .plan import format_table
    config = load(args.config, args.sets)
    check_output_dir(config.output_dir(), "output.dir")
    check_plots(config, config.output.plots, flag="klaw-ocp run --no-plots")
    plans = config.full_plan()
    print(format_table(config.body_model(), plans, config.name))
    s, w = config.solver, config.walk
    notes = []
    if w.start_from_rest:
        notes.append("starts from rest, standing on both feet")
    if w.end_at_rest:
        notes.append(f"step {plans[-1].index} closes the walk at rest (sl = 0)")
    print(f"Solver: {s.method}, {s.stance} stance, {s.intervals} intervals, tolerance {s.tolerance:g}. "
          + (" ".join(n[0].upper() + n[1:] + "." for n in notes)))
    print(f"valid: {args.config}; `klaw-ocp run` writes to {config.output_dir()}/"
          + ("" if config.output.plots else " (no plots)"))
    return EXIT_OK


def configure_plot(p: argparse.ArgumentParser) -> None:
    p.description = ("Redraw the plots of a finished run (hip_height, gait_diagram, torques, states, "
                     "legs and, from its angles.csv, joint_angles and body) from its result files "
                     "into DIR/plots/ (or --out), without solving; with --animation also walk.gif.")
    p.epilog = "example: klaw-ocp plot results/natural_walk --animation"
    p.add_argument("dir", metavar="DIR", help="a results folder written by klaw-ocp run")
    p.add_argument("--out", metavar="DIR", help="where to write the plots (default: DIR/plots/)")
    p.add_argument("--animation", action="store_true",
                   help=f"also redraw {GIF_FILE} (into DIR/, or --out; it takes a few seconds)")


def handle_plot(args: argparse.Namespace) -> int:
    from ..io import RunData, write_rendered
    run = RunData.from_folder(args.dir, what="DIR")     # refused before matplotlib is even loaded
    out = check_output_dir(args.out if args.out is not None else Path(args.dir) / PLOTS_DIR, "--out")
    from ..io.plots import render_plots
    paths = write_rendered(render_plots(run), out)
    print(f"{run.name}: wrote {len(paths)} plots to {out}/ ({', '.join(p.name for p in paths.values())})")
    if args.animation:
        from ..io.animation import write_animation
        gif = write_animation(run, (Path(args.out) if args.out else Path(args.dir)) / GIF_FILE)
        print(f"{run.name}: wrote {gif}" if gif is not None
              else f"{run.name}: no {GIF_FILE} (no angles.csv with two frames, or no completed step)")
    return EXIT_OK
