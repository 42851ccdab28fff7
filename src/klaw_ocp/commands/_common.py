"""What several subcommands share: the ``--set`` option, loading a config with its overrides,
the check of an output folder before any solving, the text of ``config.resolved.yaml``, and the
words of a command stopped by a signal or unable to write its results (the same for every
command: docs/experiments.md, "Exit codes")."""
from __future__ import annotations

import argparse
import os
import shlex
import sys
from pathlib import Path

from .. import __version__
from ..errors import ConfigError, short_repr

SET_HELP = ("override one config field by its dotted path, the value a YAML scalar validated like "
            "the file (walk.speed=4, attributes.toe_clearance=0.03, body.height=1.65, "
            "solver.method=plain-shooting); repeat for several, the last one wins; walk.steps and "
            "walk.duration replace each other")


def add_set_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", action="append", default=[], metavar="PATH=VALUE", dest="sets", help=SET_HELP)


def load(config_path, sets=(), method: str | None = None, stance: str | None = None, fps: str | None = None):
    """The validated experiment of ``config_path`` with its ``--set`` overrides and the
    ``--method``/``--stance``/``--fps`` flags folded in (so that the resolved config reproduces
    the run; ``fps`` as typed, validated like ``--set output.fps=...``)."""
    from ..config import MAX_FPS, check_stance_method, load_config
    extra = list(sets or ())
    if fps is not None and not str(fps).strip():
        raise ConfigError(f"--fps: got {short_repr(fps)}, allowed a number > 0 and <= {MAX_FPS:g} (frames per second)")
    if method:
        extra.append(f"solver.method={method}")
    if stance:
        extra.append(f"solver.stance={stance}")
    if fps is not None:
        extra.append(f"output.fps={fps}")
    config = load_config(config_path, extra)
    check_stance_method(config.solver.stance, config.solver.method)
    return config


def resolved_header(config_path, sets=(), method: str | None = None, stance: str | None = None,
                    fps: str | None = None) -> str:
    """The comment on top of ``config.resolved.yaml``: where it came from and how to rerun it."""
    flags = "".join(f" --set {shlex.quote(s)}" for s in sets or ())
    flags += f" --method {method}" if method else ""
    flags += f" --stance {stance}" if stance else ""
    flags += f" --fps {shlex.quote(fps)}" if fps is not None else ""
    return (f"Resolved by klaw_ocp {__version__} from {config_path}{flags}:\n"
            "every default filled in. Rerun with: klaw-ocp run config.resolved.yaml --out DIR")


def check_output_dir(path, field: str = "--out") -> Path:
    """``path`` as a Path if it can be the output folder of a command: an existing folder this
    process may write in, or a folder it can create (its nearest existing ancestor a folder it
    may write in). Otherwise one ConfigError line naming ``field`` (``--out``, ``output.dir``),
    before anything is solved or written. Nothing is created here."""
    text = os.fspath(path) if isinstance(path, (str, os.PathLike)) else None
    if not text or "\0" in text:
        raise ConfigError(f"{field}: got {short_repr(path)}, allowed a folder path")
    folder = Path(text)
    allowed = "a folder that exists or can be created, and that this user may write in"
    try:
        probe = folder
        while not (probe.exists() or probe.is_symlink()):
            if probe.parent == probe:
                break
            probe = probe.parent
        if probe == folder:
            if not folder.is_dir():
                kind = "a broken link" if folder.is_symlink() and not folder.exists() else "an existing file"
                raise ConfigError(f"{field}: got {short_repr(text)}, {kind}, allowed {allowed}")
            if not os.access(folder, os.W_OK | os.X_OK):
                raise ConfigError(f"{field}: got {short_repr(text)}, a folder without write permission, "
                                  f"allowed {allowed}")
            return folder
        if not probe.is_dir():
            raise ConfigError(f"{field}: got {short_repr(text)}, which lies under the file "
                              f"{short_repr(str(probe))}, allowed {allowed}")
        if not os.access(probe, os.W_OK | os.X_OK):
            raise ConfigError(f"{field}: got {short_repr(text)}, which cannot be created in "
                              f"{short_repr(str(probe))} (no write permission), allowed {allowed}")
    except OSError as exc:   # a name too long, a loop of links, ...
        raise ConfigError(f"{field}: got {short_repr(text)} ({exc.strerror or type(exc).__name__}), "
                          f"allowed {allowed}") from None
    return folder


def compile_notice():
    """The block within which a first compile of the solver kernels is said on one line of
    stderr before the pause (klaw_ocp.console.CompileNotice), for every command that solves."""
    from ..console import CompileNotice
    from ..kernels import compile_notices
    from . import PROG
    return compile_notices(CompileNotice(PROG))


def report_stop(where: str = "") -> int:
    """Print the one line of a command that Ctrl-C or SIGTERM stopped (``where``: where its
    results are) and return its exit code: ``klaw-ocp: interrupted (Ctrl-C); <where>``, exit 130,
    or ``klaw-ocp: terminated (SIGTERM); <where>``, exit 143 (128 + the signal's number)."""
    from ..stop_signals import stopped_words, terminated
    from . import EXIT_INTERRUPTED, EXIT_TERMINATED, PROG
    print(f"{PROG}: {stopped_words()}" + (f"; {where}" if where else ""), file=sys.stderr)
    return EXIT_TERMINATED if terminated() else EXIT_INTERRUPTED


def unwritten(exc: OSError) -> str:
    """What could not be written and why, as the line and summary.json's message say it:
    ``<path>: <cause>`` (``/tmp/out/walk.bvh: No space left on device``), ``the results: <cause>``
    for an error that names no file."""
    from ..errors import os_error_text
    return os_error_text(exc) if exc.filename is not None else f"the results: {os_error_text(exc)}"


def could_not_write(what: str, where: str, staging=None, kept=None) -> str:
    """A failed write (a full disk, a permission lost, a folder removed) in the words every command
    uses after ``klaw-ocp: error: ``: ``could not write <path>: <cause>; <where>`` (``what``:
    :func:`unwritten`; ``where``: where what was written is kept). ``staging``, ``kept``: the
    staging folder the file was written in and the folder it was kept as: the path is then the
    file as it is named now."""
    if staging is not None and kept is not None:
        what = what.replace(str(staging), str(kept))
    return f"could not write {what}; {where}"
