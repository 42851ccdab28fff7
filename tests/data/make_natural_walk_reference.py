"""Regenerate tests/data/natural_walk_reference.json: the natural walk solved in every mode.

    python tests/data/make_natural_walk_reference.py             # overwrites the committed reference
    python tests/data/make_natural_walk_reference.py --out x.json

Runs from any directory. Solves configs/natural_walk.yaml in each mode (solver method / stance
formulation) with the current code and writes, per mode, the walk's initial state and every
subphase's torque parameters, in the format tests/test_reference_walk.py reads (which builds its
comparison with :func:`mode_entry` below, so the two cannot drift apart). The file is replaced
atomically: an interrupted run leaves the old reference whole.

When regenerating is legitimate: only for a change that is MEANT to change the walk (the model,
a control law, the discretisation, an attribute or the config, the solver tolerance) and that
says so, after the new walk has been checked on its own (the test's independent re-integration
still passes; the parameters moved by what the change explains). Never to make
tests/test_reference_walk.py pass after a change that should leave the walk alone (refactoring,
performance work): that failure is the test doing its job.
"""
from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
import tempfile
from dataclasses import replace
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parents[1]
CONFIG = ROOT / "configs" / "natural_walk.yaml"
REFERENCE = HERE / "natural_walk_reference.json"
#: "solver method/stance formulation", in the order of the file
MODES = ("multiple-shooting/monitored", "plain-shooting/monitored", "multiple-shooting/tracking")
WHEN = ("tests/test_reference_walk.py holds today's solvers to them. Regenerate (python "
        "tests/data/make_natural_walk_reference.py) only for a change meant to change the walk (model, "
        "control laws, discretisation, attributes, config, solver tolerance) that says so, after checking "
        "the new walk (the test's independent re-integration passes, the differences are explained); never "
        "to make the test pass after a change meant to leave the walk alone (refactoring, performance work).")


def mode_spec(mode: str):
    """The WalkSpec of configs/natural_walk.yaml solved in ``mode`` ("method/stance")."""
    from klaw_ocp.config import load_config
    from klaw_ocp.walk import walk_spec
    method, stance = mode.split("/")
    return replace(walk_spec(load_config(CONFIG), method), stance=stance)


def mode_entry(walk) -> dict:
    """One mode of the file: the initial state and, per step, each subphase's parameters."""
    return {"initial_state": [float(v) for v in walk.initial_state],
            "steps": [{sub.name: {k: float(v) for k, v in sub.parameters.items()} for sub in step.subphases}
                      for step in walk.steps]}


def provenance() -> str:
    try:
        run = lambda *args: subprocess.run(["git", *args], cwd=ROOT, capture_output=True, text=True,
                                           check=True).stdout.strip()
        commit = run("rev-parse", "--short", "HEAD")
        dirty = " with local changes" if run("status", "--porcelain", "--", "src", "configs") else ""
        return f"at commit {commit}{dirty}"
    except (OSError, subprocess.CalledProcessError):
        return "outside a git checkout"


def document(entries: dict, about: str) -> dict:
    return {"about": about, "modes": {mode: entries[mode] for mode in MODES}}


def write_atomically(path: Path, doc: dict) -> None:
    """Write the JSON (one-space indent, as committed) to a temporary file beside ``path``, then
    rename it over ``path``."""
    path = Path(path)
    mode = path.stat().st_mode & 0o777 if path.exists() else 0o644
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=".tmp")
    try:
        os.fchmod(fd, mode)   # mkstemp makes it 0600
        with os.fdopen(fd, "w") as out:
            out.write(json.dumps(doc, indent=1))
            out.flush()
            os.fsync(out.fileno())
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def main(argv=None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--out", type=Path, default=REFERENCE, help=f"where to write (default {REFERENCE})")
    args = parser.parse_args(argv)
    from klaw_ocp.walk import simulate_walk
    entries, tolerances = {}, set()
    for mode in MODES:
        print(f"solving {mode} ...", file=sys.stderr)
        spec = mode_spec(mode)
        tolerances.add(f"{spec.tolerance:g}")
        entries[mode] = mode_entry(simulate_walk(spec))
    about = ("Torque parameters of every subphase of configs/natural_walk.yaml and the walk's initial state, "
             f"in each mode (solver method/stance formulation), solver tolerance {'/'.join(sorted(tolerances))}, "
             "written by "
             f"tests/data/make_natural_walk_reference.py {provenance()}. " + WHEN)
    write_atomically(args.out, document(entries, about))
    print(f"wrote {args.out}", file=sys.stderr)
    return 0


if __name__ == "__main__":
    sys.exit(main())
