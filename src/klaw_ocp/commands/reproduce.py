"""``klaw-ocp reproduce``: the paper's figures 8 and 10, the acceleration, the solver modes
compared and the paper's numbers beside ours, into results/paper/ (:mod:`klaw_ocp.reproduce`)."""
from __future__ import annotations

import argparse
import time

from . import EXIT_OK

HELP = "regenerate results/paper/: the paper's figures 8 and 10 and its numbers beside ours"


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Walk the shipped configs of the paper's figures (start_stop_2kmh, start_stop_5kmh, "
                     "natural_walk, short_steps, long_steps, accelerate; the natural walk in both solver "
                     "modes) and write fig8.png, fig10.png, acceleration.png, comparison.png/.csv, the "
                     "natural walk's hip height and gait diagram, numbers.json and README.md (our numbers "
                     "beside the paper's) to --out. Every config is checked before the first walk.")
    p.epilog = "example: klaw-ocp reproduce --out results/paper"
    p.add_argument("--configs", default="configs", metavar="DIR",
                   help="the folder with the shipped configs (default: configs)")
    p.add_argument("--out", default="results/paper", metavar="DIR", help="output folder (default: results/paper)")
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def handle(args: argparse.Namespace) -> int:
    from ..reproduce import reproduce
    from ._common import check_output_dir
    check_output_dir(args.out, "--out")
    t0 = time.perf_counter()
    written = reproduce(args.configs, args.out, progress=not args.quiet)
    print(f"reproduced the paper in {time.perf_counter() - t0:.1f} s: wrote {len(written)} files to {args.out}/ "
          f"(see {written['readme']})")
    return EXIT_OK
