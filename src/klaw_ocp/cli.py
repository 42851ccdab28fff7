"""The ``klaw-ocp`` command line.

Subcommands are registered in :data:`SUBCOMMANDS` (name -> :class:`Subcommand`); each lives in its
own module of :mod:`klaw_ocp.commands` as a function that configures its argparse sub-parser and
a handler ``(args) -> exit code``; adding one is one more dict entry.

- ``plan``: the paper's high-level concepts (section 3) for one step or every step of a config;
- ``validate``: a config checked as ``run`` checks it, and its walk plan printed, solving nothing;
- ``run``: one walk, its result files and plots; ``plot``: the plots of a finished run again;
- ``compare``: runs (solver modes, stance formulations, configs or finished folders) side by side;
- ``sweep``: a grid of config values;
- ``reproduce``: the paper's figures 8 and 10 and its numbers, into results/paper/;
- ``serve``: the live walking playground, a local web server (docs/serve.md).

Errors: every :class:`klaw_ocp.errors.KlawError` becomes one line on stderr,
``klaw-ocp: error: <message>``, and exit code 2. So does every command-line error argparse
finds (an unknown option, a bad choice, a number that is not one, a missing CONFIG, an unknown
command): one line ``klaw-ocp: error: <flag>: got <value>, allowed <...>``, no usage banner
(:class:`KlawArgumentParser`; ``klaw-ocp COMMAND --help`` shows the usage). Results that cannot
be written (an OSError: a full disk, a permission lost, a folder removed) are one line naming
the path and the cause, exit 74; Ctrl-C and SIGTERM one line, exit 130 and 143
(:mod:`klaw_ocp.stop_signals`).
"""
from __future__ import annotations

import argparse
import os
import sys
import textwrap
import warnings
from dataclasses import dataclass
from typing import Callable

from .commands import EXIT_USAGE, EXIT_WRITE_FAILED, PROG
from .commands import compare as _compare, plan as _plan, reproduce as _reproduce, run as _run, sweep as _sweep
from .commands import serve as _serve
from .commands._common import report_stop, unwritten
from .errors import ConfigError, KlawError, ResultsNotWritten, cut, one_line, short_repr
from .stop_signals import CommandSignals


class UsageError(ConfigError):
    """A command line argparse refused (an unknown option, a bad choice or number, a missing argument)."""


def _brief(text: str | None) -> str:
    """The first clause of an argument's help: what the argument is."""
    text = one_line(text or "")
    for stop in ("; ", " (default", ", repeat"):
        text = text.split(stop)[0]
    return text


class KlawArgumentParser(argparse.ArgumentParser):
    """argparse, with every error one line ``<flag>: got <value>, allowed <...>`` raised as a
    :class:`UsageError` (printed by :func:`main` like any other bad input) instead of a usage
    banner and ``sys.exit``."""

    def _action_named(self, name: str):
        for action in self._actions:
            if name in action.option_strings or name in (action.metavar, action.dest):
                return action
        return None

    @staticmethod
    def _name(action) -> str:
        if action is None:
            return "argument"
        if action.option_strings:
            return "/".join(action.option_strings)
        return action.metavar if isinstance(action.metavar, str) else action.dest

    def _get_value(self, action, arg_string):
        try:
            return super()._get_value(action, arg_string)
        except argparse.ArgumentError:
            kind = {float: "a number", int: "an integer"}.get(action.type, "a valid value")
            what = _brief(action.help)
            raise UsageError(f"{self._name(action)}: got {short_repr(arg_string)}, allowed {kind}"
                             + (f" ({what})" if what else "")) from None

    def _check_value(self, action, value):
        if action.choices is not None and value not in action.choices:
            choices = ", ".join(map(str, action.choices))
            raise UsageError(f"{self._name(action)}: got {short_repr(value)}, allowed one of {choices}")

    def known_options(self) -> str:
        return ", ".join(a.option_strings[-1] for a in self._actions if a.option_strings)

    def error(self, message: str):
        """argparse's remaining errors (missing arguments, an option without its value, an
        ambiguous abbreviation), as one line. (Python 3.12+ raises some of them as an
        ArgumentError without an argument; the message says which.)"""
        message = one_line(message)
        required = "the following arguments are required: "
        if required in message:
            name = message.split(required, 1)[1].split(", ")[0]
            action = self._action_named(name)
            what = _brief(action.help) if action is not None else ""
            raise UsageError(f"{name}: got nothing, allowed one argument" + (f": {what}" if what else "")
                             + f" (`{self.prog} --help`)")
        if "ambiguous option: " in message:
            option = message.split("ambiguous option: ", 1)[1].split(" could match ")[0]
            matches = message.split(" could match ", 1)[1] if " could match " in message else ""
            raise UsageError(f"{option}: got an ambiguous abbreviation, allowed one of {matches}")
        exc = sys.exc_info()[1]
        if isinstance(exc, argparse.ArgumentError) and exc.argument_name:
            action = self._action_named(exc.argument_name)
            detail = one_line(exc.message)
            if detail.startswith("expected"):        # --speed with no value
                what = _brief(action.help) if action is not None else ""
                raise UsageError(f"{exc.argument_name}: got nothing, allowed {detail.replace('expected ', '')}"
                                 + (f" ({what})" if what else ""))
            if detail.startswith("ignored explicit argument "):   # --quiet=3
                value = detail[len("ignored explicit argument "):]
                raise UsageError(f"{exc.argument_name}: got the value {value}, allowed no value (a flag)")
            raise UsageError(f"{exc.argument_name}: got {short_repr(detail)}, allowed "
                             f"the forms `{self.prog} --help` shows")
        raise UsageError(f"{self.prog}: got {short_repr(message)}, allowed the forms `{self.prog} --help` shows")


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
    "serve": Subcommand(_serve.HELP, _serve.configure, _serve.handle),
}


def build_parser() -> argparse.ArgumentParser:
    parser = KlawArgumentParser(
        prog=PROG, description="KLAW (Bruderlin & Calvert 1989): goal-directed dynamic walking.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, command in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=command.help, formatter_class=argparse.RawDescriptionHelpFormatter)
        command.configure(p)
        if p.description:   # the raw formatter keeps the epilog's example lines; wrap the prose here
            p.description = textwrap.fill(p.description, width=90)
        p.set_defaults(handler=command.handler)
    return parser


def parse(parser: KlawArgumentParser, argv: list[str] | None) -> argparse.Namespace:
    """The command line as a namespace, or a :class:`UsageError` naming the first thing wrong."""
    args, extra = parser.parse_known_args(argv)
    handler = getattr(args, "handler", None)
    if handler is None:
        raise UsageError(f"COMMAND: got nothing (a COMMAND is required), allowed one of {', '.join(SUBCOMMANDS)}")
    if extra:
        sub = parser._subparsers._group_actions[0].choices[args.command]   # noqa: SLF001
        first = extra[0]
        if first.startswith("-") and len(first) > 1:
            option = cut(first.split("=")[0], 40)
            raise UsageError(f"{option}: got an unknown option, allowed the options of "
                             f"{PROG} {args.command}: {sub.known_options()}")
        raise UsageError(f"{PROG} {args.command}: got the extra argument {short_repr(first, 60)}, allowed "
                         f"the arguments `{PROG} {args.command} --help` shows")
    return args


def _one_line_warning(message, category, filename, lineno, file=None, line=None) -> None:
    """The package's own notes (``klaw_ocp: ...``, e.g. a damaged kernel rebuilt) as one line on
    stderr, in the command's voice; any other warning as Python shows it."""
    text = str(message)
    if text.startswith("klaw_ocp: "):
        from tqdm import tqdm   # clears and redraws a progress bar around the line
        tqdm.write(f"{PROG}: {' '.join(text[len('klaw_ocp: '):].split())}", file=sys.stderr)
    else:
        _show_warning(message, category, filename, lineno, file, line)


_show_warning = warnings.showwarning


def main(argv: list[str] | None = None) -> int:
    """Run ``klaw-ocp``; returns the exit code (0 ok, 2 bad input, 3 a subphase did not converge,
    74 the results could not be written, 130 Ctrl-C, 143 SIGTERM; :mod:`klaw_ocp.commands`)."""
    warnings.showwarning = _one_line_warning
    parser = build_parser()
    try:
        with CommandSignals():       # SIGTERM stops a command as Ctrl-C does
            try:
                args = parse(parser, argv)
            except SystemExit as exc:  # --help and --version print and exit 0
                return exc.code if isinstance(exc.code, int) else EXIT_USAGE
            return args.handler(args)
    except ResultsNotWritten as exc:
        print(f"{PROG}: error: {one_line(exc)}", file=sys.stderr)
        return EXIT_WRITE_FAILED
    except KlawError as exc:
        message = " ".join(str(exc).split("\n"))
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt as exc:   # Ctrl-C or SIGTERM the command did not report (before or after a walk)
        return report_stop(getattr(exc, "where", ""))
    except BrokenPipeError:
        # The reader (e.g. `| head`) closed the pipe: stop quietly, as the Python docs advise,
        # and keep the interpreter from failing again when it flushes stdout at exit.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1
    except OSError as exc:    # a write outside a results folder (klaw-ocp plot's --out): the same one line
        print(f"{PROG}: error: could not write {unwritten(exc)}", file=sys.stderr)
        return EXIT_WRITE_FAILED


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
