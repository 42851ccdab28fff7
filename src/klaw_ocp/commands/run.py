"""``klaw-ocp run``, ``validate`` and ``plot``: one walk from a config file (section 2.4: high
level, then the low level step by step), its check without solving, and its plots redrawn from a
finished results folder.

``run`` writes into the results folder every file of the registry
(:data:`klaw_ocp.result_files.registry.RUN_FILES`, which names them once): ``summary.json``,
``dynamics.csv``, ``events.csv``, the body at ``output.fps`` frames per second (``angles.csv``,
``walk.bvh``, ``walk.mot``), ``config.resolved.yaml`` (the config with its ``--set``,
``--method``, ``--stance`` and ``--fps`` folded in and every default filled in: running it again
gives the same ``dynamics.csv`` bytes) and, unless ``--no-plots`` or ``output.plots: false``, the
plots of :data:`klaw_ocp.figures.registry.PLOTS` in ``plots/``; with ``output.animation: true``
(the shipped configs) and without ``--no-animation``, ``walk.gif`` (:mod:`klaw_ocp.figures.animation`,
docs/gif.md), after the plots and independent of them. The registries are read here without
loading CasADi or matplotlib.

Each step is written as it completes (:class:`klaw_ocp.result_files.run_writer.RunWriter`, the walk's
``on_step``) into a folder beside the results folder, which replaces it whole when the walk ends
(:class:`klaw_ocp.result_files.results_folder.StagedFolder`); a walk that fails (exit 3), is interrupted
(Ctrl-C: exit 130, SIGTERM: 143) or cannot be written (a full disk: exit 74) keeps its completed
steps and leaves earlier results untouched. The helpers below
(:func:`walk_into`, :func:`finish_into`, :func:`report_unfinished`, :func:`keeping`) are shared by
``compare``, ``sweep`` and ``reproduce``; docs/experiments.md has the rules.
"""
from __future__ import annotations

import argparse
import sys
from contextlib import contextmanager
from pathlib import Path

from .. import choices
from ..errors import one_line
from ..result_files.registry import RUN_FILES
from ..stop_signals import stopped_words
from . import EXIT_OK, EXIT_SOLVER_FAILED, PROG
from ._common import (add_set_option, check_output_dir, could_not_write, load, report_stop, resolved_header,
                      unwritten)

RUN_HELP = "simulate a configured walk and write its result files and plots"
VALIDATE_HELP = "check a config and print its walk plan, solving nothing"
PLOT_HELP = "redraw the plots of a finished results folder, solving nothing"
PLOTS_DIR = RUN_FILES["plots"].folder
GIF_FILE = RUN_FILES["animation"].name


def configure_run(p: argparse.ArgumentParser) -> None:
    p.description = ("Simulate the configured walk step by step and write summary.json, dynamics.csv, "
                     "events.csv, angles.csv (the body's 56 angles at every frame), config.resolved.yaml, "
                     "the plots (plots/*.png) and, with output.animation, walk.gif to --out (default "
                     "results/<name>/). Each step is written as it completes, into a folder beside --out "
                     "that replaces the earlier results when the walk ends. A subphase that does not "
                     "converge is reported on one line (step, subphase, residual, cause) and exits 3; "
                     "results that cannot be written (a full disk) exit 74, Ctrl-C 130, SIGTERM 143; "
                     "either way the completed steps are kept, and earlier results stay untouched.")
    p.epilog = ("example: klaw-ocp run configs/natural_walk.yaml --set walk.speed=4 "
                "--method plain-shooting --out /tmp/slow")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: output.dir or results/<name>/)")
    p.add_argument("--method", choices=choices.METHODS,
                   help="solver mode (default: the config's solver.method)")
    p.add_argument("--stance", choices=choices.STANCES,
                   help="stance formulation: the paper's monitored pa, or pa optimised over the grid "
                        "to track the hip sinusoid (multiple shooting only; default: solver.stance)")
    p.add_argument("--fps", metavar="FPS",
                   help="frames per second of angles.csv, a number > 0 and <= 1000 (default: output.fps, 30)")
    add_set_option(p)
    p.add_argument("--no-plots", action="store_true", help="skip the plots (as output.plots: false)")
    p.add_argument("--no-animation", action="store_true",
                   help="skip walk.gif (as output.animation: false; the plots are not affected)")
    add_force_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def add_force_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--force", action="store_true",
                   help="write into --out even if it is a non-empty folder klaw-ocp did not write (its "
                        "other files are kept; klaw-ocp's replace those of the same name)")


def handle_run(args: argparse.Namespace) -> int:
    config = load(args.config, args.sets, args.method, args.stance, args.fps)
    out = check_output_dir(args.out if args.out is not None else config.output_dir(),
                           "--out" if args.out is not None else "output.dir")
    plots = config.output.plots and not args.no_plots
    animation = config.output.animation and not args.no_animation
    if plots or animation:               # the drawing processes import matplotlib while the walk is solved
        from ..figures.render_pool import prewarm
        prewarm()
    from ..result_files.results_folder import StagedFolder        # the solvers: only for a valid run
    from ..result_files.run_writer import RunWriter
    from ..walk import walk_spec
    staged = StagedFolder(out, "run", force=args.force)        # refused here, before any solving
    header = resolved_header(args.config, args.sets, args.method, args.stance, args.fps)
    writer = None
    with keeping(staged, lambda: f"{len(writer.done) if writer else 0} completed step(s)",
                 lambda text: writer and writer.record_write_error(text)):
        writer = RunWriter(staged.open(), config.resolved_yaml(header))     # the walk carries output.fps
        walk, outcome, failure = walk_into(writer, walk_spec(config), quiet=args.quiet)
        paths, times, outcome, _ = finish_into(writer, walk, outcome, plots=plots, animation=animation)
        if outcome != "ok":
            return report_unfinished(staged, outcome, failure, f"{len(walk.steps)} completed step(s)")
        staged.commit()
    rtf = walk.duration / walk.wall_s if walk.wall_s else float("inf")
    n_plots = sum(path.parent.name == PLOTS_DIR for path in paths.values())
    plots = f"; {n_plots} plots in {times['plots']:.2f} s" if times["plots"] is not None else ""
    if times["animation"] is not None:
        plots += f"; {GIF_FILE} in {times['animation']:.2f} s"
    # the real-time factor is the walk's; a first run's one-off compile is said beside it
    compiled = (f", plus {walk.compile_s:.1f} s compiling the solver kernels once for this machine"
                if walk.compile_s > 0 else "")
    print(f"{walk.spec.name}: {len(walk.steps)} steps, {walk.duration:.2f} s of walking in {walk.wall_s:.2f} s "
          f"({rtf:.1f}x real time, {walk.spec.method}, {walk.spec.stance} stance){compiled}{plots}; wrote {out}/")
    return EXIT_OK


def walk_into(writer, spec, quiet: bool = True):
    """Walk ``spec`` with ``writer`` writing each step as it completes; returns (walk, outcome,
    failure): outcome "ok", "failed" (failure: the ConvergenceError) or "interrupted". If the
    solver kernels have to be compiled (the first run on a machine), one line on stderr says so
    before the pause, even with ``quiet``: it is the one pause a user cannot otherwise explain. The
    body's kernels are compiled (or loaded) first, under the same line: not counted in the walk's
    ``compile_s``, and no second pause after the walk."""
    from ..body_motion import prepare_kernels
    from ..errors import ConvergenceError
    from ..walk import Walk, simulate_walk
    from ._common import compile_notice
    try:
        with compile_notice():
            prepare_kernels()       # the body's, which the files need after the walk (the same notice)
            return simulate_walk(spec, progress=not quiet, on_step=writer.step), "ok", None
    except ConvergenceError as exc:
        return exc.partial, "failed", exc
    except KeyboardInterrupt as exc:      # klaw_ocp.errors.Interrupted, or Ctrl-C before the first step
        walk = getattr(exc, "partial", None)
        if walk is None:
            walk = Walk(spec, status="interrupted", message=stopped_words())
        return walk, "interrupted", None


def finish_into(writer, walk, outcome: str, plots: bool = False, animation: bool = False):
    """:meth:`RunWriter.finish` of a walk that ended with ``outcome`` (an interrupted one without
    plots or walk.gif), the plots and walk.gif, then the final summary.json, last (a summary
    saying "ok" comes with every file); Ctrl-C or SIGTERM while it writes makes the run
    "interrupted" and writes the summary only. Returns (paths, times, outcome, the walk's RunData
    or None if interrupted here)."""
    from ..stop_signals import requested
    interrupted = outcome == "interrupted"
    try:
        paths, run = writer.finish(walk, summary=False)
        times = {"plots": None, "animation": None}
        drawing = not interrupted and bool(walk.steps)
        plots, animation = plots and drawing, animation and drawing
        if plots or animation:
            from ..figures.render_pool import render_outputs       # on every core (docs/performance.md)
            drawn, times = render_outputs(run, writer.folder / PLOTS_DIR if plots else None,
                                          writer.folder / GIF_FILE if animation else None)
            paths.update(drawn)
        if outcome == "ok" and requested():
            # a stop signal that never surfaced (CasADi's wrappers drop a KeyboardInterrupt raised
            # inside them): the run still ends as interrupted, as the user asked
            raise KeyboardInterrupt
        paths["summary"] = writer.write_summary(run.summary)
        return paths, times, outcome, run
    except KeyboardInterrupt:
        walk.status, walk.message = "interrupted", f"{stopped_words()} while writing the results"
        try:
            writer.finish(walk, body=False)
        except KeyboardInterrupt:
            pass
        return {}, {"plots": None, "animation": None}, "interrupted", None


@contextmanager
def keeping(staged, what, on_write_error=None):
    """Whatever else ends the command in the block keeps what was written, as a failed run keeps
    it (the earlier results untouched); ``what()`` says how much was written:

    - an OSError (a full disk, a permission lost, a folder removed): ``on_write_error(text)``
      records it (a run's summary.json: "incomplete"), then :class:`~klaw_ocp.errors.ResultsNotWritten`,
      one line naming the path, the cause and where the results are (exit 74);
    - a stop signal the command did not report itself: :class:`~klaw_ocp.errors.Interrupted`
      whose ``where`` says where the results are (:func:`klaw_ocp.cli.main`'s one line, 130 or 143);
    - a KlawError (bad input found late, e.g. a sweep's grid): on to its own one line, what was
      written kept without a word;
    - anything else (a bug): one line saying where, and the exception goes on with its traceback."""
    from ..errors import Interrupted, KlawError, ResultsNotWritten
    try:
        yield
    except KlawError:
        staged.keep()
        raise
    except BrokenPipeError:      # stdout's reader went away (`| head`): klaw_ocp.cli ends quietly
        staged.keep()
        raise
    except OSError as exc:
        text, staging = unwritten(exc), staged.path
        if on_write_error is not None:
            on_write_error(text)
        where = kept_where(staged, what())
        raise ResultsNotWritten(could_not_write(text, where, staging, staged.kept)) from None
    except KeyboardInterrupt as exc:
        stopped = Interrupted(getattr(exc, "partial", None))
        stopped.where = kept_where(staged, what())
        raise stopped from None
    except Exception as exc:
        where = kept_where(staged, what())
        text = one_line(exc)[:200]
        print(f"{PROG}: error: unexpected {type(exc).__name__}" + (f" ({text})" if text else "") + f"; {where}",
              file=sys.stderr)
        raise


def kept_where(staged, what: str) -> str:
    """Keep what ``staged`` holds; the words that say where it is (``what``: how much it is)."""
    from ..result_files.results_folder import kept_phrase
    kept = staged.keep()
    return kept_phrase(kept, staged) if kept is None else f"{what} {kept_phrase(kept, staged)}"


def report_unfinished(staged, outcome: str, failure, what: str) -> int:
    """Keep the results of a command that failed (``failure``: the ConvergenceError, or a
    sentence) or was interrupted, print its one line and return its exit code."""
    where = kept_where(staged, what)
    if outcome == "failed":
        print(f"{PROG}: error: {failure_sentence(failure)}; {where}", file=sys.stderr)
        return EXIT_SOLVER_FAILED
    return report_stop(where)


def failure_sentence(failure) -> str:
    """A ConvergenceError in words: its step, subphase and residual, then its real cause."""
    if isinstance(failure, str) or not hasattr(failure, "cause"):
        return one_line(failure)
    where = f"{failure.where}: " if failure.where else ""
    return (f"{where}step {failure.step}, subphase {failure.subphase!r}: did not converge "
            f"(residual {failure.residual:.3g}): {failure.cause}")


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
    from ..result_files import RunData
    run = RunData.from_folder(args.dir, what="DIR")     # refused before matplotlib is even loaded
    out = check_output_dir(args.out if args.out is not None else Path(args.dir) / PLOTS_DIR, "--out")
    from ..figures.render_pool import render_outputs
    gif = (Path(args.out) if args.out else Path(args.dir)) / GIF_FILE if args.animation else None
    paths, _ = render_outputs(run, out, gif)
    gif = paths.pop("animation", None)
    print(f"{run.name}: wrote {len(paths)} plots to {out}/ ({', '.join(p.name for p in paths.values())})")
    if args.animation:
        print(f"{run.name}: wrote {gif}" if gif is not None
              else f"{run.name}: no {GIF_FILE} (no angles.csv with two frames, or no completed step)")
    return EXIT_OK
