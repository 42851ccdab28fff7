"""Project hygiene: the README quick start and CI run the same test command; CI is runnable."""
import os
import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def test_quick_start_is_exactly_two_commands():
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    section = text.split("## Quick start", 1)[1]
    block = re.search(r"```bash\n(.*?)```", section, re.S).group(1)
    assert block.splitlines() == ["pip install -e . && klaw-ocp run configs/natural_walk.yaml",
                                  'pip install -e ".[test]" && pytest']


def test_ci_installs_from_its_own_files_into_a_fresh_environment_and_runs_the_readme_test_command():
    """CI sees what a new user gets: a new virtual environment (removed at the end), the project
    installed there from pyproject.toml with today's packages, then README's test command."""
    ci = ROOT / ".ci" / "run"
    assert os.access(ci, os.X_OK)
    lines = [l.strip() for l in ci.read_text(encoding="utf-8").splitlines()]
    assert lines[0] == "#!/usr/bin/env bash" and "set -euo pipefail" in lines
    venv = next(i for i, l in enumerate(lines) if re.match(r'python3? -m venv "\$scratch/venv"$', l))
    activate = lines.index('source "$scratch/venv/bin/activate"')
    install = lines.index('pip install -e ".[test]"')
    assert venv < activate < install
    assert any(l.startswith("trap ") and 'rm -rf "$scratch"' in l for l in lines[:venv])
    assert lines[-1] == "pytest"


def test_each_solver_choice_is_named_once():
    """The solvers' registry, the config schema and every command's --method take their names from
    klaw_ocp.choices: a new mode is its solver module plus one entry."""
    import argparse
    import typing

    from klaw_ocp import choices
    from klaw_ocp.cli import build_parser
    from klaw_ocp.config import SolverConfig
    from klaw_ocp.solvers import NLP_CHOICES, SOLVERS

    assert tuple(SOLVERS) == choices.METHODS
    fields = SolverConfig.model_fields
    assert typing.get_args(fields["method"].annotation) == choices.METHODS
    assert typing.get_args(fields["nlp"].annotation) == choices.NLPS == NLP_CHOICES
    assert typing.get_args(fields["stance"].annotation) == choices.STANCES
    assert typing.get_args(fields["lock_rule"].annotation) == choices.LOCK_RULES
    defaults = SolverConfig()
    assert (defaults.method, defaults.intervals, defaults.tolerance, defaults.max_iterations, defaults.nlp,
            defaults.stance, defaults.lock_rule) == (
        choices.DEFAULT_METHOD, choices.DEFAULT_INTERVALS, choices.DEFAULT_TOLERANCE,
        choices.DEFAULT_MAX_ITERATIONS, choices.DEFAULT_NLP, choices.DEFAULT_STANCE, choices.DEFAULT_LOCK_RULE)
    parser = build_parser()
    commands = next(a for a in parser._actions if isinstance(a, argparse._SubParsersAction)).choices
    for name in ("run", "sweep"):
        method = next(a for a in commands[name]._actions if "--method" in a.option_strings)
        extra = (choices.ALL_METHODS,) if name == "sweep" else ()
        assert tuple(method.choices) == choices.METHODS + extra, name
    source = "\n".join(p.read_text(encoding="utf-8") for p in (ROOT / "src" / "klaw_ocp").rglob("*.py")
                       if p.name != "choices.py")
    for name in choices.METHODS:
        assert not re.search(rf"""["']{name}["']""", source), f"{name!r} written outside klaw_ocp.choices"
