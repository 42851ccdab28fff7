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


def test_ci_installs_from_its_own_files_and_runs_the_readme_test_command():
    ci = ROOT / ".ci" / "run"
    assert os.access(ci, os.X_OK)
    lines = [l.strip() for l in ci.read_text(encoding="utf-8").splitlines()]
    assert lines[0] == "#!/usr/bin/env bash" and "set -euo pipefail" in lines
    assert 'python -m pip install -e ".[test]"' in lines
    assert lines[-1] == "pytest"
