"""What several subcommands share: the ``--set`` option, loading a config with its overrides,
and the text of ``config.resolved.yaml``."""
from __future__ import annotations

import argparse
import shlex

from .. import __version__

SET_HELP = ("override one config field by its dotted path, the value a YAML scalar validated like "
            "the file (walk.speed=4, attributes.toe_clearance=0.03, body.height=1.65, "
            "solver.method=plain-shooting); repeat for several, the last one wins")


def add_set_option(p: argparse.ArgumentParser) -> None:
    p.add_argument("--set", action="append", default=[], metavar="PATH=VALUE", dest="sets", help=SET_HELP)


def load(config_path, sets=(), method: str | None = None, stance: str | None = None, fps: str | None = None):
    """The validated experiment of ``config_path`` with its ``--set`` overrides and the
    ``--method``/``--stance``/``--fps`` flags folded in (so that the resolved config reproduces
    the run; ``fps`` as typed, validated like ``--set output.fps=...``)."""
    from ..config import check_stance_method, load_config
    extra = list(sets or ())
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
