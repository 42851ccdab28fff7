"""``klaw-ocp reproduce``: the paper's figures 8, 9 and 10, the acceleration, the solver modes
compared and the paper's numbers beside ours, into results/paper/ (:mod:`klaw_ocp.reproduce`)."""
from __future__ import annotations

import argparse
import time

from . import EXIT_OK
from .run import add_force_option, keeping, report_unfinished

HELP = "regenerate results/paper/: the paper's figures 8, 9 and 10 and its numbers beside ours"


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Walk the shipped configs of the paper's figures (start_stop_2kmh, start_stop_5kmh, "
                     "natural_walk, short_steps, long_steps, accelerate; the natural walk in both solver "
                     "modes, and 8 steps of it with pelvic_list 5 and 12 deg) and write fig8.png, "
                     "figure9_pelvic_list.png, fig10.png, acceleration.png, comparison.png/.csv, the "
                     "natural walk's hip height and gait diagram, numbers.json and README.md (our numbers "
                     "beside the paper's) to --out. Every config is checked before the first walk. Exit code 3 "
                     "if a walk does not converge, 74 if the results cannot be written, 130 on Ctrl-C, "
                     "143 on SIGTERM (what was drawn is kept beside the earlier results).")
    p.epilog = "example: klaw-ocp reproduce --out results/paper"
    p.add_argument("--configs", default="configs", metavar="DIR",
                   help="the folder with the shipped configs (default: configs)")
    p.add_argument("--out", default="results/paper", metavar="DIR", help="output folder (default: results/paper)")
    add_force_option(p)
    p.add_argument("--quiet", action="store_true", help="no progress bars")


def handle(args: argparse.Namespace) -> int:
    from ..errors import ConvergenceError
    from ..result_files.results_folder import StagedFolder
    from ..reproduce import check_configs, reproduce
    from ..stop_signals import requested
    from ._common import check_output_dir, compile_notice
    t0 = time.perf_counter()
    out = check_output_dir(args.out, "--out")
    check_configs(args.configs)                                   # before any walk
    staged = StagedFolder(out, "reproduce", force=args.force)    # refused here, before any walk
    staging = staged.open()
    with keeping(staged, lambda: "what was drawn"), compile_notice():
        try:
            written = reproduce(args.configs, staging, progress=not args.quiet)
            if requested():      # a stop signal CasADi's wrappers swallowed: stopped all the same
                raise KeyboardInterrupt
        except ConvergenceError as exc:
            return report_unfinished(staged, "failed", exc, "the figures drawn so far")
        except KeyboardInterrupt:
            return report_unfinished(staged, "interrupted", None, "the figures drawn so far")
        staged.commit()           # in the block: a commit that cannot be written is one line too
    print(f"reproduced the paper in {time.perf_counter() - t0:.1f} s: wrote {len(written)} files to {out}/ "
          f"(see {out / written['readme'].name})")
    return EXIT_OK
