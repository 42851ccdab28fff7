"""The ``klaw-ocp`` command line.

Subcommands are registered in :data:`SUBCOMMANDS` (name -> :class:`Subcommand`); each lives in its
own module of :mod:`klaw_ocp.commands` as a function that configures its argparse sub-parser and
a handler ``(args) -> exit code``; adding one is one more dict entry.

- ``plan``: the paper's high-level concepts (section 3) for one step or every step of a config;
- ``validate``: a config checked as ``run`` checks it, and its walk plan printed, solving nothing;
- ``run``: one walk, its result files and plots; ``plot``: the plots of a finished run again;
- ``compare``: runs (solver modes, stance formulations, configs or finished folders) side by side;
- ``sweep``: a grid of config values;
- ``reproduce``: the paper's figures 8 and 10 and its numbers, into results/paper/.

Errors: every :class:`klaw_ocp.errors.KlawError` becomes one line on stderr,
``klaw-ocp: error: <message>``, and exit code 2 (argparse's own usage errors also exit 2).
"""
from __future__ import annotations

import argparse
import os
import sys
import textwrap
from dataclasses import dataclass
from typing import Callable

from .commands import EXIT_INTERRUPTED, EXIT_USAGE, PROG
from .commands import compare as _compare, plan as _plan, reproduce as _reproduce, run as _run, sweep as _sweep
from .errors import KlawError


@dataclass(frozen=True)
class Subcommand:
    """One ``klaw-ocp <name>`` command: its help line, argument setup and handler."""

    help: str
    configure: Callable[[argparse.ArgumentParser], None]
    handler: Callable[[argparse.Namespace], int]


# ----------------------------------------------------------------------------- registry, main

#: Every subcommand by name. Another command is one more entry here.
SUBCOMMANDS: dict[str, Subcommand] = {
    "plan": Subcommand(_plan.HELP, _plan.configure, _plan.handle),
    "validate": Subcommand(_run.VALIDATE_HELP, _run.configure_validate, _run.handle_validate),
    "run": Subcommand(_run.RUN_HELP, _run.configure_run, _run.handle_run),
    "plot": Subcommand(_run.PLOT_HELP, _run.configure_plot, _run.handle_plot),
    "compare": Subcommand(_compare.HELP, _compare.configure, _compare.handle),
    "sweep": Subcommand(_sweep.HELP, _sweep.configure, _sweep.handle),
    "reproduce": Subcommand(_reproduce.HELP, _reproduce.configure, _reproduce.handle),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, description="KLAW (Bruderlin & Calvert 1989): goal-directed dynamic walking.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, command in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=command.help, formatter_class=argparse.RawDescriptionHelpFormatter)
        command.configure(p)
        if p.description:   # the raw formatter keeps the epilog's example lines; wrap the prose here
            p.description = textwrap.fill(p.description, width=90)
        p.set_defaults(handler=command.handler)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``klaw-ocp``; returns the exit code (0 ok, 2 bad input, 3 a subphase did not converge,
    130 Ctrl-C; :mod:`klaw_ocp.commands`)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse reports usage errors itself and exits 2 (--help: 0)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_usage(sys.stderr)
        print(f"{PROG}: error: a COMMAND is required, allowed: {', '.join(SUBCOMMANDS)}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return handler(args)
    except KlawError as exc:
        message = " ".join(str(exc).split("\n"))
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:   # Ctrl-C outside a walk (the commands report their own)
        print(f"{PROG}: interrupted (Ctrl-C)", file=sys.stderr)
        return EXIT_INTERRUPTED
    except BrokenPipeError:
        # The reader (e.g. `| head`) closed the pipe: stop quietly, as the Python docs advise,
        # and keep the interpreter from failing again when it flushes stdout at exit.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
