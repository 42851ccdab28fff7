"""The registries name every file of a results folder once (klaw_ocp.result_files.registry, and
the plots in klaw_ocp.figures.registry): a run writes exactly what they list, the writers, the
folder staging and the commands read the names from them, and the frame rate a run was asked for
reaches every file that needs it (issue 33)."""
import ast
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from klaw_ocp.cli import main
from klaw_ocp.figures.registry import PLOTS
from klaw_ocp.result_files import RunData, render_run
from klaw_ocp.result_files import registry
from klaw_ocp.result_files.registry import MARKER, RUN_FILES

ROOT = Path(__file__).resolve().parents[1]
FPS = 60


@pytest.fixture(scope="module")
def run_dir(tmp_path_factory):
    """A three-step walk run with the CLI at --fps 60, its plots and walk.gif drawn."""
    base = tmp_path_factory.mktemp("registry")
    config = base / "short.yaml"
    config.write_text(yaml.safe_dump({"name": "short", "body": {"height": 1.8, "mass": 80},
                                      "walk": {"speed": 5.0, "steps": 3}, "output": {"animation": True}}))
    out = base / "run"
    assert main(["run", str(config), "--out", str(out), "--fps", str(FPS), "--quiet"]) == 0
    return out


def _listing(folder: Path) -> set:
    return {p.relative_to(folder).as_posix() for p in folder.rglob("*") if p.is_file()}


def _expected(plots: bool, animation: bool) -> set:
    """The registry's files of a run with these options, the plots expanded by their registry."""
    names = set()
    for name in registry.run_file_names(plots=plots, animation=animation):
        if "*" in name:
            folder = RUN_FILES["plots"].folder
            names |= {f"{folder}/{plot.file}" for plot in PLOTS.values()}
        else:
            names.add(name)
    return names | {MARKER}


def test_a_run_writes_exactly_the_files_the_registry_lists(run_dir, tmp_path):
    assert _listing(run_dir) == _expected(plots=True, animation=True)
    config = run_dir / RUN_FILES["resolved"].name
    assert main(["run", str(config), "--out", str(tmp_path / "bare"), "--no-plots", "--no-animation", "--quiet"]) == 0
    assert _listing(tmp_path / "bare") == _expected(plots=False, animation=False)
    every = {f.key for f in RUN_FILES.values() if f.option is None}
    assert every == {"summary", "dynamics", "events", "angles", "bvh", "mot", "resolved"}


def test_every_renderer_the_registries_name_exists():
    for entry in RUN_FILES.values():
        assert callable(registry.load(entry.renderer)), entry.key
    for plot in PLOTS.values():
        assert callable(registry.load(plot.figure)), plot.name


def test_the_registries_load_neither_casadi_nor_matplotlib():
    code = ("import sys, klaw_ocp.result_files.registry, klaw_ocp.figures.registry, klaw_ocp.commands.run; "
            "print(sorted({m.split('.')[0] for m in sys.modules} & {'casadi', 'matplotlib'}))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True).stdout
    assert out.strip() == "[]"


def _string_constants(path: Path):
    """The string literals of a module, its docstrings left out (they may name files in prose)."""
    tree = ast.parse(path.read_text(encoding="utf-8"))
    docstrings = {id(node.body[0].value) for node in ast.walk(tree)
                  if isinstance(node, (ast.Module, ast.ClassDef, ast.FunctionDef, ast.AsyncFunctionDef))
                  and node.body and isinstance(node.body[0], ast.Expr)
                  and isinstance(node.body[0].value, ast.Constant)}
    for node in ast.walk(tree):
        if isinstance(node, ast.Constant) and isinstance(node.value, str) and id(node) not in docstrings:
            yield node.lineno, node.value


def test_no_file_name_is_written_outside_the_registries():
    """results_folder, run_writer, run_data, the writers and the commands take every result file's
    name from the registries: no literal "dynamics.csv" anywhere else in the package."""
    names = {f.name for f in RUN_FILES.values() if "*" not in f.name}
    names |= {p.file for p in PLOTS.values()}
    names |= {registry.COMPARISON_CSV, registry.COMPARISON_PNG, registry.SWEEP_CSV, registry.SWEEP_PNG,
              registry.NUMBERS_JSON, MARKER}
    package = ROOT / "src" / "klaw_ocp"
    owners = {package / "result_files" / "registry.py", package / "figures" / "registry.py"}
    found = [f"{path.relative_to(package)}:{line}: {text!r}"
             for path in sorted(package.rglob("*.py")) if path not in owners
             for line, text in _string_constants(path) if text in names]
    assert not found, "file names outside the registries:\n" + "\n".join(found)


def test_the_results_folder_accepts_what_the_registry_lists():
    from klaw_ocp.result_files import results_folder
    run = registry.COMMAND_FOLDERS["run"]
    assert set(run) == {f.name for f in RUN_FILES.values()} | {RUN_FILES["plots"].folder}
    assert results_folder.COMMAND_FOLDERS is registry.COMMAND_FOLDERS
    assert registry.KEY_FILES["run"] == RUN_FILES["summary"].name


# -- the frame rate, carried from --fps to every file that needs it ----------------------------
def test_the_runs_fps_reaches_the_bvh_the_mot_and_angles_csv(run_dir):
    summary = json.loads((run_dir / RUN_FILES["summary"].name).read_text())
    assert summary["fps"] == FPS
    bvh = (run_dir / RUN_FILES["bvh"].name).read_text().splitlines()
    assert f"Frame Time: {1 / FPS:.17g}" in bvh and float(f"{1 / FPS:.17g}") == 1 / FPS
    angles = RunData.from_folder(run_dir).angles["time"]
    np.testing.assert_allclose(np.diff(angles), 1 / FPS, atol=1e-12)
    mot = (run_dir / RUN_FILES["mot"].name).read_text().split("endheader\n")[1].splitlines()
    times = np.array([float(row.split("\t")[0]) for row in mot[1:]])
    assert len(times) == len(angles)
    np.testing.assert_allclose(np.diff(times), 1 / FPS, atol=1e-9)


def test_plot_of_the_folder_keeps_its_fps(run_dir, tmp_path):
    files = [RUN_FILES[key].name for key in ("summary", "bvh")]
    before = {name: (run_dir / name).read_bytes() for name in files}
    assert main(["plot", str(run_dir), "--out", str(tmp_path / "plots")]) == 0
    assert {name: (run_dir / name).read_bytes() for name in files} == before
    run = RunData.from_folder(run_dir)
    assert run.fps == FPS

    def motion_header(text: bytes) -> list:          # MOTION, Frames: n, Frame Time: dt
        lines = text.split(b"\n")
        return lines[lines.index(b"MOTION"):][:3]
    assert motion_header(render_run(run, ["bvh"])["bvh"][1]) == motion_header(before[RUN_FILES["bvh"].name])


def test_a_folder_without_fps_in_its_summary_reads_it_from_config_resolved(run_dir, tmp_path):
    import shutil
    old = tmp_path / "old"
    shutil.copytree(run_dir, old)
    summary_path = old / RUN_FILES["summary"].name
    summary = json.loads(summary_path.read_text())
    del summary["fps"]                                      # as written before summary.json recorded it
    summary_path.write_text(json.dumps(summary))
    assert RunData.from_folder(old).fps == FPS
    (old / RUN_FILES["resolved"].name).unlink()             # and before config.resolved.yaml: 30 fps
    assert RunData.from_folder(old).fps == 30.0
