"""``klaw-ocp compare``: runs side by side (the two solver modes of section 4.1, the two stance
formulations, or different configs), from config files it solves or results folders it reads.

Every input is checked before the first walk starts. Each solved run is also written, as ``run``
writes it (without plots), to ``<out>/runs/<name>-<method>-<stance>/``, so that a comparison can be
redone later from folders without solving. The comparison itself (:mod:`klaw_ocp.compare`) and its
picture (:mod:`klaw_ocp.io.compare_plot`) only read results.
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import ConfigError, out_of_range
from . import EXIT_NOT_CONVERGED, EXIT_OK, PROG
from ._common import add_set_option, check_output_dir, load, resolved_header

HELP = "compare runs: solver modes, stance formulations, configs or finished results folders"
METHODS = ("multiple-shooting", "plain-shooting")
STANCES = ("monitored", "tracking")
RUNS_DIR = "runs"


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Compare runs: each INPUT is a config file (solved here, once per --method and "
                     "--stance) or a results folder written by klaw-ocp run (read, not solved). With "
                     "one config the default is both solver modes. Writes comparison.csv (one row per "
                     "step, subphase and run: the torque-profile parameters with units, residual, "
                     "iterations, solve time, and the differences to the first run) and "
                     "comparison.png to --out (default results/<name>-compare/), each solved run to "
                     "<out>/runs/, and prints the largest differences. Exit code 1 if a walk did not "
                     "converge (the others are still compared).")
    p.epilog = ("examples:\n  klaw-ocp compare configs/natural_walk.yaml\n"
                "  klaw-ocp compare configs/natural_walk.yaml --method multiple-shooting --stance monitored,tracking\n"
                "  klaw-ocp compare configs/short_steps.yaml configs/long_steps.yaml\n"
                "  klaw-ocp compare results/natural_walk results/natural_walk-ps")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="a config file or a results folder")
    p.add_argument("--method", metavar="M[,M...]",
                   help="solver modes for the config inputs: multiple-shooting, plain-shooting or both "
                        "(default: both for a single config, else each config's solver.method)")
    p.add_argument("--stance", metavar="S[,S...]",
                   help="stance formulations for the config inputs: monitored, tracking (default: "
                        "each config's solver.stance)")
    add_set_option(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<first name>-compare/)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def _choices(text: str | None, flag: str, allowed: tuple, both: bool = False) -> list | None:
    if text is None:
        return None
    items = [t.strip() for t in text.split(",")]
    if both and items == ["both"]:
        return list(allowed)
    if not items or any(t not in allowed for t in items) or len(set(items)) != len(items):
        extra = ", or both" if both else ""
        raise ConfigError(out_of_range(flag, text, f"a comma list of distinct {', '.join(allowed)}{extra}"))
    return items


def plan_runs(args: argparse.Namespace) -> list[dict]:
    """Every run to compare, in order, each checked: ``{"folder": path}`` or ``{"config": ...}``."""
    from ..config import check_stance_method
    methods = _choices(args.method, "--method", METHODS, both=True)
    stances = _choices(args.stance, "--stance", STANCES)
    configs = [i for i in args.inputs if not Path(i).is_dir()]
    if not configs and (methods or stances or args.sets):
        raise ConfigError("--method/--stance/--set: got only results folders, allowed with a config INPUT "
                          "(a folder's run is read as it was solved)")
    if len(args.inputs) == 1 and configs and methods is None:
        methods = list(METHODS)
    runs = []
    for text in args.inputs:
        if Path(text).is_dir():
            runs.append({"folder": Path(text)})
            continue
        if not Path(text).is_file():
            raise ConfigError(out_of_range("INPUT", text, "a config file or a results folder written by klaw-ocp run"))
        base = load(text, args.sets)
        for method in methods or [base.solver.method]:
            for stance in stances or [base.solver.stance]:
                check_stance_method(stance, method, prefix=f"{text} with --method {method}: ")
                config = load(text, args.sets, method, stance)
                runs.append({"config": config, "path": text, "method": method, "stance": stance,
                             "sets": list(args.sets)})
    if len(runs) < 2:
        raise ConfigError(f"compare: got {len(runs)} run, allowed at least 2 (two INPUTs, or one config "
                          f"with two --method or --stance values)")
    return runs


def handle(args: argparse.Namespace) -> int:
    from ..compare import comparison_csv, comparison_rows, comparison_stats, comparison_table
    from ..io import RunData, write_rendered
    from ..io.compare_plot import comparison_figure
    from ..io.plot_style import png_bytes

    planned = plan_runs(args)           # every input checked before the first walk
    first = planned[0]
    name = first["config"].name if "config" in first else RunData.from_folder(first["folder"], "INPUT").name
    out = check_output_dir(args.out if args.out is not None else Path("results") / f"{name}-compare",
                           "--out")
    runs, failed = [], []
    for item in planned:
        if "folder" in item:
            runs.append(RunData.from_folder(item["folder"], what="INPUT"))
            continue
        run, failure = _solve(item, out, quiet=args.quiet)
        runs.append(run)
        if failure:
            failed.append(failure)
    rows = comparison_rows(runs)
    files = {"csv": ("comparison.csv", comparison_csv(rows).encode("utf-8")),
             "png": ("comparison.png", png_bytes(comparison_figure(runs)))}
    paths = write_rendered(files, out)
    print(comparison_table(comparison_stats(runs)))
    print(f"wrote {paths['csv']} and {paths['png']}")
    for message in failed:
        print(f"{PROG}: error: {message}", file=sys.stderr)
    return EXIT_NOT_CONVERGED if failed else EXIT_OK


def _solve(item: dict, out: Path, quiet: bool):
    """Walk one planned config run and write it to ``out/runs/``; returns (RunData, failure or None)."""
    from ..errors import ConvergenceError
    from ..io import RunData
    from ..walk import simulate_walk, walk_spec
    from .run import write_run

    config = item["config"]
    failure = None
    try:
        walk = simulate_walk(walk_spec(config), progress=not quiet)
    except ConvergenceError as exc:
        walk, failure = exc.partial, f"{item['path']} ({item['method']}, {item['stance']} stance): {exc}"
    folder = out / RUNS_DIR / f"{config.name}-{item['method']}-{item['stance']}"
    header = resolved_header(item["path"], item["sets"], item["method"], item["stance"])
    write_run(walk, config.resolved_yaml(header), folder, config.output.fps, plots=False)
    return RunData.from_walk(walk), failure
