"""What several subcommands share: the ``--set`` option, loading a config with its overrides,
the check of an output folder before any solving, and the text of ``config.resolved.yaml``."""
from __future__ import annotations

import argparse
import os
import shlex
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
    from ..solvers.kernels import compile_notices
    from . import PROG
    return compile_notices(CompileNotice(PROG))
