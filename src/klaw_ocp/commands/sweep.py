"""``klaw-ocp sweep``: walk one config over a grid of values (:mod:`klaw_ocp.sweep`, docs/sweep.md)."""
from __future__ import annotations

import argparse
import os
import sys

from ..errors import ConfigError
from . import EXIT_NOT_CONVERGED, PROG

HELP = "walk a grid of config values and write sweep.csv and sweep.png"


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Walk every combination of the --vary values (their Cartesian product, the "
                     "first path varying slowest) and write sweep.csv (one row per walk and method) "
                     "and sweep.png (a convergence and wall-time map) to --out (default "
                     "results/<name>-sweep/). Every combination is validated before any walk "
                     "starts; a walk that fails does not stop the others. Exit code 0 if every "
                     "walk converged, 1 otherwise, 2 for bad input. See docs/sweep.md.")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--vary", action="append", required=True, metavar="PATH=VALUES",
                   help="a dotted config path (walk.speed, body.height, attributes.trunk_lean, "
                        "solver.intervals, ...) and its values: a comma list of YAML scalars "
                        "(1,3,5 or true,false) or a range start:stop:step that includes stop when "
                        "it is on the grid (0.5:8:0.5); repeat for a grid")
    p.add_argument("--method", choices=("multiple-shooting", "plain-shooting", "both"),
                   help="solver mode(s) (default: each combination's solver.method)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: the number of CPUs; 1 runs in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help='run the walks on a dask.distributed cluster (tcp://host:8786); needs '
                        'pip install -e ".[cluster]"')
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<name>-sweep/)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.epilog = "example: klaw-ocp sweep configs/natural_walk.yaml --vary walk.speed=1:7:1 --method both"


def handle(args: argparse.Namespace) -> int:
    from ..sweep import counts, default_out_dir, parse_vary, run_sweep, summary_line, write_sweep

    vary: dict[str, list] = {}
    for text in args.vary:
        path, values = parse_vary(text)
        if path in vary:
            raise ConfigError(f"--vary {path}: got the path twice, allowed each path once")
        vary[path] = values
    from ._common import check_output_dir
    check_output_dir(args.out if args.out is not None else default_out_dir(args.config),
                     "--out")
    rows = run_sweep(args.config, vary, methods=args.method, workers=args.workers,
                     scheduler=args.scheduler, progress=not args.quiet and sys.stderr.isatty())
    out = args.out if args.out is not None else default_out_dir(args.config)
    paths = write_sweep(rows, list(vary), out, title=f"{PROG} sweep {os.path.basename(args.config)}")
    print(summary_line(rows, paths))
    n = counts(rows)
    return 0 if n["ok"] == len(rows) else EXIT_NOT_CONVERGED
