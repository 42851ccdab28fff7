"""``klaw-ocp sweep``: walk one config over a grid of values (:mod:`klaw_ocp.sweep`, docs/sweep.md)."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from .. import choices
from ..errors import ConfigError
from . import EXIT_OK, EXIT_SOLVER_FAILED, EXIT_WRITE_FAILED, PROG
from ._common import could_not_write, report_stop, unwritten
from .run import add_force_option, keeping, kept_where

HELP = "walk a grid of config values and write sweep.csv and sweep.png"


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Walk every combination of the --vary values (their Cartesian product, the "
                     "first path varying slowest) and write sweep.csv (one row per walk and method) "
                     "and sweep.png (a convergence and wall-time map) to --out (default "
                     "results/<name>-sweep/). Every combination is validated before any walk "
                     "starts; a walk that fails does not stop the others. Exit code 0 if every "
                     "walk converged, 3 otherwise (the sweep is still written; a walk whose worker process "
                     "died is 'lost', the others go on), 2 for bad input, 74 if its files cannot be "
                     "written, 130 for Ctrl-C and 143 for SIGTERM (the finished walks are kept). See "
                     "docs/sweep.md.")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--vary", action="append", required=True, metavar="PATH=VALUES",
                   help="a dotted config path (walk.speed, body.height, attributes.trunk_lean, "
                        "solver.intervals, ...) and its values: a comma list of YAML scalars "
                        "(1,3,5 or true,false) or a range start:stop:step that includes stop when "
                        "it is on the grid (0.5:8:0.5); repeat for a grid")
    p.add_argument("--method", choices=(*choices.METHODS, choices.ALL_METHODS),
                   help="solver mode(s) (default: each combination's solver.method)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: the number of CPUs; 1 runs in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help='run the walks on a dask.distributed cluster (tcp://host:8786); needs '
                        'pip install -e ".[cluster]"')
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<name>-sweep/)")
    add_force_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.epilog = "example: klaw-ocp sweep configs/natural_walk.yaml --vary walk.speed=1:7:1 --method both"


def handle(args: argparse.Namespace) -> int:
    """The sweep (SIGTERM stops it as Ctrl-C does: :func:`klaw_ocp.cli.main` installs
    :class:`klaw_ocp.stop_signals.CommandSignals` for every command)."""
    try:
        return _sweep(args)
    except KeyboardInterrupt as exc:
        # a stop the sweep could not answer where it came (before the first walk, or a second
        # one while it was ending): its one line all the same, with where its results are
        return report_stop(getattr(exc, "where", ""))


def _sweep(args: argparse.Namespace) -> int:
    from ..config_paths import combination_label
    from ..errors import Interrupted
    from ..result_files.atomic import atomic_write_text
    from ..result_files.registry import SWEEP_CSV, SWEEP_PNG
    from ..result_files.results_folder import StagedFolder
    from ..stop_signals import Deferred
    from ..sweep import (append_sweep_row, counts, default_out_dir, parse_vary, run_sweep, summary_line,
                         sweep_csv, write_sweep)

    vary: dict[str, list] = {}
    for text in args.vary:
        path, values = parse_vary(text)
        if path in vary:
            raise ConfigError(f"--vary {path}: got the path twice, allowed each path once")
        vary[path] = values
    from ._common import check_output_dir, compile_notice
    out = check_output_dir(args.out if args.out is not None else default_out_dir(args.config), "--out")
    staged = StagedFolder(out, "sweep", force=args.force)       # refused here, before any walk
    written: list[dict] = []

    def staging() -> Path:     # the staging folder opens with the first finished walk
        return staged.path if staged.path is not None else staged.open()

    def on_row(row):
        # sweep.csv grows walk by walk, one appended line each (rewriting the whole file after
        # every walk cost time growing with the square of the walks); append_sweep_row says why
        # no finished walk is lost
        append_sweep_row(staging() / SWEEP_CSV, row, list(vary))
        written.append(row)

    with keeping(staged, lambda: "the walks finished so far"), compile_notice():
        try:
            rows = run_sweep(args.config, vary, methods=args.method, workers=args.workers,
                             scheduler=args.scheduler, progress=not args.quiet and sys.stderr.isatty(),
                             on_row=on_row)
        except Interrupted as exc:
            # the sweep is stopping: a second signal waits until the finished walks are kept
            with Deferred(second_raises=False):
                try:
                    if exc.partial:        # the finished walks again, atomically and in grid order
                        atomic_write_text(staging() / SWEEP_CSV, sweep_csv(exc.partial, list(vary)))
                except OSError as error:
                    return _not_written(staged, error, f"{len(written)} finished walk(s)")
                return report_stop(_where_kept(staged, f"{len(exc.partial)} finished walk(s)"))
        except OSError as exc:     # a line of sweep.csv (the workers are stopped)
            return _not_written(staged, exc, f"{len(written)} finished walk(s)")
        try:
            write_sweep(rows, list(vary), staging(), title=f"{PROG} sweep {os.path.basename(args.config)}")
        except KeyboardInterrupt:
            with Deferred(second_raises=False):
                return report_stop(_where_kept(staged, f"all {len(rows)} walks ({SWEEP_PNG} not drawn)"))
        except OSError as exc:
            return _not_written(staged, exc, f"all {len(rows)} walks")
        try:
            staged.commit()      # a stop signal while the folders are swapped waits for its end
        except KeyboardInterrupt:       # one just before (writing the marker): its one line too
            with Deferred(second_raises=False):
                return report_stop(_where_kept(staged, f"all {len(rows)} walks"))
        except OSError as exc:
            return _not_written(staged, exc, f"all {len(rows)} walks")
    print(summary_line(rows, {"csv": out / SWEEP_CSV, "png": out / SWEEP_PNG}))
    n = counts(rows)
    if n["ok"] == len(rows):
        return EXIT_OK
    # a walk that does not converge is one of the sweep's results: the folder is complete
    first = next(r for r in rows if r["status"] != "ok")
    label = combination_label({k: first[k] for k in vary})
    print(f"{PROG}: error: {len(rows) - n['ok']} of {len(rows)} walks did not converge, failed or were lost, "
          f"the first {label} ({first['method']}): {first['message']}; see {out / SWEEP_CSV}", file=sys.stderr)
    return EXIT_SOLVER_FAILED


def _where_kept(staged, what: str) -> str:
    """Keep what was written and say where (the staging folder itself if it cannot be moved)."""
    try:
        return kept_where(staged, what)
    except OSError:
        return f"{what} left in {staged.path}" if staged.path is not None else "nothing written"


def _not_written(staged, exc: OSError, what: str) -> int:
    """A file of the sweep could not be written (a full disk, a permission, a folder removed):
    the one line names the file and the cause, what was written is kept; exit 74."""
    staging = staged.path
    where = _where_kept(staged, what)
    print(f"{PROG}: error: {could_not_write(unwritten(exc), where, staging, staged.kept)}", file=sys.stderr)
    return EXIT_WRITE_FAILED
