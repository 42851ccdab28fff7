"""``klaw-ocp run --set``, ``validate``, ``config.resolved.yaml``, ``plot`` and ``compare`` from the
command line (issue #20): what each writes, that overrides are validated like the file, that
validate and plot and a comparison of folders solve nothing."""
import csv
import json
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml

from klaw_ocp.cli import main

ROOT = Path(__file__).resolve().parents[1]
CONFIGS = sorted((ROOT / "configs").glob("*.yaml"))
PLOT_FILES = {"hip_height.png", "gait_diagram.png", "torques.png", "states.png", "legs.png",
              "joint_angles.png", "body.png"}


def _one_error_line(capsys) -> str:
    captured = capsys.readouterr()
    lines = captured.err.strip().splitlines()
    assert len(lines) == 1, captured.err
    assert lines[0].startswith("klaw-ocp: error: ") and "Traceback" not in captured.err
    return lines[0]


# ---------------------------------------------------------------------------------------- --set

def test_set_overrides_fields_of_every_section(short_config, tmp_path):
    out = tmp_path / "o"
    code = main(["run", str(short_config), "--out", str(out), "--quiet", "--no-plots",
                 "--set", "walk.speed=4", "--set", "attributes.toe_clearance=0.03", "--set", "body.height=1.65"])
    assert code == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["steps"][0]["speed_kmh"] == pytest.approx(4.0)
    assert summary["body"]["height"] == 1.65 and summary["attributes"]["toe_clearance"] == 0.03
    resolved = yaml.safe_load((out / "config.resolved.yaml").read_text())
    assert resolved["walk"]["speed"] == 4 and resolved["body"]["height"] == 1.65
    assert resolved["attributes"]["toe_clearance"] == 0.03


@pytest.mark.parametrize("override, field", [
    ("walk.speed=-1", "walk.speed"),            # a value outside its range
    ("walk.speed=fast", "walk.speed"),          # a value of the wrong type
    ("walk.sped=4", "walk.sped"),               # a path that does not exist
    ("walk.speed.x=3", "walk.speed.x"),         # a path through a number
    ("walk.speed", "--set"),                    # no value
    ("=4", "--set"),                            # no path
    ("attributes.no_such=1", "no_such"),        # an unknown attribute
])
def test_set_refuses_a_bad_path_or_value_in_one_line(override, field, short_config, tmp_path, capsys, no_solving):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--set", override]) == 2
    line = _one_error_line(capsys)
    assert field in line and "allowed" in line
    assert not out.exists()


def test_set_uses_the_sweep_parser():
    """One syntax for both flags: a --set value parses as each --vary value does."""
    from klaw_ocp.config_paths import parse_set, parse_vary
    for text in ("4", "0.03", "1e-3", "true", "null", "plain-shooting", "20"):
        assert parse_set(f"walk.speed={text}") == (parse_vary(f"walk.speed={text}")[0], parse_vary(f"walk.speed={text}")[1][0])


# ------------------------------------------------------------------------------------ validate

@pytest.mark.parametrize("config", CONFIGS, ids=[c.stem for c in CONFIGS])
def test_validate_accepts_every_shipped_config_and_writes_nothing(config, tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    assert main(["validate", str(config)]) == 0
    out = capsys.readouterr().out
    assert "valid:" in out and "theta1" in out and "t_ds" in out
    assert list(tmp_path.iterdir()) == []


def test_validate_prints_every_step_including_the_closing_one(capsys):
    assert main(["validate", str(ROOT / "configs/start_stop_2kmh.yaml")]) == 0
    out = capsys.readouterr().out
    rows = [line.split() for line in out.splitlines() if line.strip() and line.split()[0].isdigit()]
    assert [int(r[0]) for r in rows] == list(range(9))           # 8 steps and the closing one
    assert float(rows[-1][3]) == 0.0                              # the closing step's sl
    assert "closes the walk at rest" in out


def test_validate_refuses_a_bad_override_in_one_line(capsys):
    assert main(["validate", str(ROOT / "configs/natural_walk.yaml"), "--set", "walk.speed=-1"]) == 2
    assert "walk.speed: got -1" in _one_error_line(capsys)


def test_validate_refuses_tracking_with_plain_shooting(capsys):
    code = main(["validate", str(ROOT / "configs/natural_walk.yaml"), "--set", "solver.stance=tracking",
                 "--set", "solver.method=plain-shooting"])
    assert code == 2 and "solver.stance" in _one_error_line(capsys)


def test_validate_imports_no_solver_and_compiles_nothing(tmp_path):
    """validate loads neither CasADi nor a solver module, so it cannot build or compile a kernel."""
    script = ("import sys; from klaw_ocp.cli import main; code = main(['validate', sys.argv[1]]); "
              "loaded = [m for m in sys.modules if m == 'casadi' or m.startswith('klaw_ocp.solvers')]; "
              "print('LOADED', loaded); sys.exit(code)")
    done = subprocess.run([sys.executable, "-c", script, str(ROOT / "configs/accelerate.yaml")],
                          capture_output=True, text=True, cwd=tmp_path,
                          env={**__import__("os").environ, "KLAW_OCP_CACHE_DIR": str(tmp_path / "cache")})
    assert done.returncode == 0, done.stderr
    assert "LOADED []" in done.stdout
    assert not (tmp_path / "cache").exists()


# --------------------------------------------------------------------- resolved config, plots

def test_resolved_config_reproduces_the_walk_byte_for_byte(short_config, tmp_path):
    first, second = tmp_path / "first", tmp_path / "second"
    assert main(["run", str(short_config), "--out", str(first), "--quiet", "--no-plots",
                 "--method", "plain-shooting", "--set", "walk.speed=4.5"]) == 0
    resolved = yaml.safe_load((first / "config.resolved.yaml").read_text())
    assert resolved["solver"]["method"] == "plain-shooting"          # the flag is folded in
    assert set(resolved["attributes"]) > {"toe_clearance", "pelvic_list"}   # every default filled in
    assert main(["run", str(first / "config.resolved.yaml"), "--out", str(second), "--quiet", "--no-plots"]) == 0
    assert (first / "dynamics.csv").read_bytes() == (second / "dynamics.csv").read_bytes()
    assert (first / "config.resolved.yaml").read_text().split("\n", 2)[2] == \
        (second / "config.resolved.yaml").read_text().split("\n", 2)[2]


def test_run_writes_the_plots_and_plot_redraws_them_without_solving(short_config, tmp_path, monkeypatch, capsys):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet"]) == 0
    assert {p.name for p in (out / "plots").iterdir()} == PLOT_FILES
    for png in (out / "plots").iterdir():
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_mode & 0o044 == 0o044
    import klaw_ocp.walk
    monkeypatch.setattr(klaw_ocp.walk, "simulate_walk", lambda *a, **k: pytest.fail("solved"))
    redrawn = tmp_path / "redrawn"
    assert main(["plot", str(out), "--out", str(redrawn)]) == 0
    assert {p.name for p in redrawn.iterdir()} == PLOT_FILES


def test_no_plots_skips_them_and_removes_stale_ones(short_config, tmp_path):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet"]) == 0
    assert any((out / "plots").iterdir())
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-plots"]) == 0
    assert not (out / "plots").exists()          # the rerun replaced the folder whole
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--set", "output.plots=false"]) == 0
    assert not (out / "plots").exists()


def test_plot_refuses_a_folder_that_is_not_a_run(tmp_path, capsys):
    assert main(["plot", str(tmp_path)]) == 2
    assert "DIR" in _one_error_line(capsys)


# -------------------------------------------------------------------------------------- compare

def _csv_rows(path):
    with open(path, newline="", encoding="utf-8") as handle:
        return list(csv.DictReader(handle))


def test_compare_one_config_runs_both_modes_and_matches_two_separate_runs(short_config, tmp_path, capsys):
    out = tmp_path / "cmp"
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == 0
    rows = _csv_rows(out / "comparison.csv")
    assert len(rows) == 2 * 4 * 2                                   # steps x subphases x modes
    assert {r["run"] for r in rows} == {"short (multiple-shooting, monitored stance)",
                                        "short (plain-shooting, monitored stance)"}
    assert (out / "comparison.png").read_bytes()[:4] == b"\x89PNG"
    table = capsys.readouterr().out
    assert "hip height" in table and "iterations" in table
    # the same two walks run separately
    for method in ("multiple-shooting", "plain-shooting"):
        assert main(["run", str(short_config), "--out", str(tmp_path / method), "--quiet", "--no-plots",
                     "--method", method]) == 0
    ms, ps = (json.loads((tmp_path / m / "summary.json").read_text()) for m in ("multiple-shooting", "plain-shooting"))
    for row in (r for r in rows if r["run"].startswith("short (plain")):
        k, name = int(row["step"]), row["subphase"]
        a = next(s for s in ms["steps"][k]["subphases"] if s["name"] == name)["parameters"]
        b = next(s for s in ps["steps"][k]["subphases"] if s["name"] == name)["parameters"]
        for param in a:
            column = next(c for c in row if c.startswith(f"d_{param} ["))
            assert float(row[column]) == pytest.approx(b[param] - a[param], rel=1e-9, abs=1e-12)
    # and the hip-height difference of the two separate runs
    from klaw_ocp.compare import comparison_stats
    from klaw_ocp.result_files import RunData
    separate = comparison_stats([RunData.from_folder(tmp_path / m) for m in ("multiple-shooting", "plain-shooting")])
    inside = comparison_stats([RunData.from_folder(p) for p in sorted((out / "runs").iterdir())])
    assert inside["runs"][1]["hip_y"]["value"] == pytest.approx(separate["runs"][1]["hip_y"]["value"], rel=1e-9, abs=1e-15)
    direct = np.max(np.abs(np.array([float(r["hip_y"]) for r in _csv_rows(tmp_path / "multiple-shooting" / "dynamics.csv")])
                           - np.array([float(r["hip_y"]) for r in _csv_rows(tmp_path / "plain-shooting" / "dynamics.csv")])))
    assert separate["runs"][1]["hip_y"]["value"] == pytest.approx(direct, rel=1e-9, abs=1e-15)


def test_compare_of_results_folders_solves_nothing(short_config, tmp_path, monkeypatch, capsys):
    for method in ("multiple-shooting", "plain-shooting"):
        assert main(["run", str(short_config), "--out", str(tmp_path / method), "--quiet", "--no-plots",
                     "--method", method]) == 0
    import klaw_ocp.walk
    monkeypatch.setattr(klaw_ocp.walk, "simulate_walk", lambda *a, **k: pytest.fail("solved a walk"))
    out = tmp_path / "cmp"
    assert main(["compare", str(tmp_path / "multiple-shooting"), str(tmp_path / "plain-shooting"),
                 "--out", str(out)]) == 0
    assert len(_csv_rows(out / "comparison.csv")) == 16
    assert not (out / "runs").exists()


@pytest.mark.parametrize("args, field", [
    (["--method", "fast"], "--method"),
    (["--stance", "monitored,monitored"], "--stance"),
    (["--method", "plain-shooting", "--stance", "tracking"], "solver.stance"),
    (["--method", "plain-shooting"], "compare"),                     # one run is nothing to compare
    (["--set", "walk.speed=-2"], "walk.speed"),
])
def test_compare_refuses_bad_input_before_solving(args, field, short_config, tmp_path, capsys, no_solving):
    out = tmp_path / "cmp"
    assert main(["compare", str(short_config), "--out", str(out), *args]) == 2
    assert field in _one_error_line(capsys)
    assert not out.exists()


def test_compare_refuses_solver_flags_with_only_folders_and_a_missing_input(tmp_path, capsys, no_solving):
    (tmp_path / "a").mkdir()
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "a"), "--method", "plain-shooting"]) == 2
    assert "--method" in _one_error_line(capsys)
    assert main(["compare", str(tmp_path / "nope.yaml"), str(tmp_path / "a")]) == 2
    assert "INPUT" in _one_error_line(capsys)
    assert main(["compare", str(tmp_path / "a"), str(tmp_path / "a")]) == 2        # not a results folder
    assert "INPUT" in _one_error_line(capsys)
