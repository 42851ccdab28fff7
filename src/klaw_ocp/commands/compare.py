"""``klaw-ocp compare``: runs side by side (the two solver modes of section 4.1, the two stance
formulations, or different configs), from config files it solves or results folders it reads.

Every input is checked before the first walk starts. Each solved run is also written, as ``run``
writes it (without plots), to ``<out>/runs/<name>-<method>-<stance>/``, so that a comparison can be
redone later from folders without solving. The comparison itself (:mod:`klaw_ocp.compare`) and its
picture (:mod:`klaw_ocp.figures.compare_plot`) only read results.
"""
from __future__ import annotations

import argparse
from pathlib import Path

from .. import choices
from ..errors import ConfigError, out_of_range
from ..result_files.registry import COMPARE_RUNS
from . import EXIT_OK
from ._common import add_set_option, check_output_dir, load, resolved_header
from .run import add_force_option, keeping, report_unfinished

HELP = "compare runs: solver modes, stance formulations, configs or finished results folders"
METHODS = choices.METHODS
STANCES = choices.STANCES


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Compare runs: each INPUT is a config file (solved here, once per --method and "
                     "--stance) or a results folder written by klaw-ocp run (read, not solved). With "
                     "one config the default is both solver modes. Writes comparison.csv (one row per "
                     "step, subphase and run: the torque-profile parameters with units, residual, "
                     "iterations, solve time, and the differences to the first run) and "
                     "comparison.png to --out (default results/<name>-compare/), each solved run to "
                     "<out>/runs/, and prints the largest differences. Exit code 3 if a walk did not "
                     "converge (the others are still compared; the earlier results stay and the new "
                     "ones are kept beside them), 74 if the results cannot be written (a full disk), "
                     "130 on Ctrl-C, 143 on SIGTERM.")
    p.epilog = ("examples:\n  klaw-ocp compare configs/natural_walk.yaml\n"
                "  klaw-ocp compare configs/natural_walk.yaml --method multiple-shooting --stance monitored,tracking\n"
                "  klaw-ocp compare configs/short_steps.yaml configs/long_steps.yaml\n"
                "  klaw-ocp compare results/natural_walk results/natural_walk-ps")
    p.add_argument("inputs", nargs="+", metavar="INPUT", help="a config file or a results folder")
    p.add_argument("--method", metavar="M[,M...]",
                   help=f"solver modes for the config inputs: {', '.join(choices.METHODS)} or {choices.ALL_METHODS} "
                        "(default: both for a single config, else each config's solver.method)")
    p.add_argument("--stance", metavar="S[,S...]",
                   help="stance formulations for the config inputs: monitored, tracking (default: "
                        "each config's solver.stance)")
    add_set_option(p)
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<first name>-compare/)")
    add_force_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def _choices(text: str | None, flag: str, allowed: tuple, both: bool = False) -> list | None:
    if text is None:
        return None
    items = [t.strip() for t in text.split(",")]
    if both and items == [choices.ALL_METHODS]:
        return list(allowed)
    if not items or any(t not in allowed for t in items) or len(set(items)) != len(items):
        extra = f", or {choices.ALL_METHODS}" if both else ""
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
    from ..result_files import RunData, write_rendered
    from ..result_files.registry import COMPARISON_CSV, COMPARISON_PNG
    from ..result_files.results_folder import StagedFolder

    planned = plan_runs(args)           # every input checked before the first walk
    first = planned[0]
    name = first["config"].name if "config" in first else RunData.from_folder(first["folder"], "INPUT").name
    out = check_output_dir(args.out if args.out is not None else Path("results") / f"{name}-compare",
                           "--out")
    staged = StagedFolder(out, "compare", force=args.force)     # refused here, before any solving
    staging = staged.open()
    runs, failed = [], []
    with keeping(staged, lambda: "the runs solved so far"):
        solved = 0
        for item in planned:
            if "folder" in item:
                runs.append(RunData.from_folder(item["folder"], what="INPUT"))
                _carry_over(item["folder"], staged, staging)
                continue
            run, outcome, failure = _solve(item, staging, quiet=args.quiet)
            if outcome == "interrupted":
                return report_unfinished(staged, outcome, None, f"{solved} solved run(s) and the interrupted one")
            solved += 1
            runs.append(run)
            if failure is not None:
                failed.append(failure)
        from ..figures.compare_plot import comparison_figure
        from ..figures.plot_style import png_bytes
        try:
            rows = comparison_rows(runs)
            files = {"csv": (COMPARISON_CSV, comparison_csv(rows).encode("utf-8")),
                     "png": (COMPARISON_PNG, png_bytes(comparison_figure(runs)))}
            write_rendered(files, staging)
        except KeyboardInterrupt:
            return report_unfinished(staged, "interrupted", None, "every run solved (the comparison not drawn)")
        stats = comparison_stats(runs)
        if not failed:
            staged.commit()       # in the block: a commit that cannot be written is one line too
    print(comparison_table(stats))
    if failed:
        # the comparison is written, but of a walk that stopped early: the earlier results stay
        return report_unfinished(staged, "failed", "; ".join(failed), "every run and the comparison")
    print(f"wrote {out / COMPARISON_CSV} and {out / COMPARISON_PNG}")
    return EXIT_OK


def _carry_over(folder: Path, staged, staging: Path) -> None:
    """An INPUT folder inside --out (``compare results/x-compare/runs/*``) would go with the folder
    it is in: copy it to the same place in the new one."""
    import os
    import shutil
    source = Path(os.path.realpath(folder))
    try:
        rel = source.relative_to(staged.target)
    except ValueError:
        return
    if rel.parts and not (staging / rel).exists():
        shutil.copytree(source, staging / rel, symlinks=True)


def _solve(item: dict, staging: Path, quiet: bool):
    """Walk one planned config run into ``staging/runs/`` as ``run`` writes it (without plots),
    step by step; returns (RunData, outcome, failure sentence or None)."""
    from ..result_files.results_folder import mark_folder
    from ..result_files.run_writer import RunWriter
    from ..walk import walk_spec
    from .run import failure_sentence, finish_into, walk_into

    config = item["config"]
    folder = staging / COMPARE_RUNS / f"{config.name}-{item['method']}-{item['stance']}"
    folder.mkdir(parents=True, exist_ok=True)
    header = resolved_header(item["path"], item["sets"], item["method"], item["stance"])
    writer = RunWriter(folder, config.resolved_yaml(header))
    walk, outcome, failure = walk_into(writer, walk_spec(config), quiet)
    _, _, outcome, run = finish_into(writer, walk, outcome)
    mark_folder(folder, "run")
    text = (f"{item['path']} ({item['method']}, {item['stance']} stance): {failure_sentence(failure)}"
            if outcome == "failed" else None)
    return run, outcome, text
