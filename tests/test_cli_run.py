"""``klaw-ocp run`` (issue #4): result files, and a failure that still writes completed steps."""
import csv
import json

import pytest

from klaw_ocp.cli import main

REQUIRED_COLUMNS = {"t", "step", "subphase", "w", "theta1", "theta2", "theta3", "theta4", "wd", "theta1d",
                    "theta2d", "theta3d", "theta4d", "hip_x", "hip_y", "F_w", "F_theta1", "F_theta2",
                    "F_theta3", "F_theta4"}
PLAN_KEYS = {"speed_kmh", "step_length_m", "step_frequency_spm", "t_cycle_s", "t_step_s", "t_ds_s",
             "t_stance_s", "t_swing_s", "w_m", "theta1_rad", "theta3_rad"}


def test_run_writes_summary_and_dynamics(short_config, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--method", "plain-shooting"]) == 0
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "ok" and summary["method"] == "plain-shooting"
    assert summary["body"]["height"] == 1.8 and summary["wall_s"] > 0 and summary["compile_s"] >= 0
    assert len(summary["steps"]) == 2
    for step in summary["steps"]:
        assert PLAN_KEYS <= set(step)
        assert [s["name"] for s in step["subphases"]] == ["stance", "swing1", "swing2", "swing3"]
        for sub in step["subphases"]:
            assert sub["residual"] <= 1e-6 and sub["iterations"] >= 1 and sub["parameters"]
    rows = list(csv.DictReader((out / "dynamics.csv").open()))
    assert REQUIRED_COLUMNS <= set(rows[0])
    times = [float(r["t"]) for r in rows]
    assert times == sorted(times) and times[-1] == pytest.approx(summary["simulated_s"])
    assert {r["subphase"] for r in rows} == {"double_support", "swing1", "swing2", "swing3"}
    assert "2 steps" in capsys.readouterr().out


def test_run_failure_writes_completed_steps(short_config, tmp_path, capsys, fail_at_step):
    fail_at_step(1, "swing2", 0.031)
    out = tmp_path / "out"
    assert main(["run", str(short_config), "--out", str(out), "--quiet"]) == 3
    # (the session's first walk may also say that it compiles the solver kernels, tests/test_first_run.py)
    err = [line for line in capsys.readouterr().err.strip().splitlines()
           if not line.startswith("klaw-ocp: compiling the solver kernels")]
    assert len(err) == 1 and "step 1" in err[0] and "swing2" in err[0] and "0.031" in err[0]
    assert "forced for the test" in err[0] and f"written to {out}" in err[0]
    assert "Traceback" not in err[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps_completed"] == 1 and len(summary["steps"]) == 1
    assert summary["failure"]["step"] == 1 and summary["failure"]["subphase"] == "swing2"


def test_run_bad_config_exits_2(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("name: bad\nbody: {height: 1.8, mass: 80}\nwalk: {speed: -3, steps: 2}\n")
    assert main(["run", str(bad), "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "walk.speed" in err[0]
    assert not (tmp_path / "o").exists()


def test_run_tracking_stance_with_plain_shooting_exits_2(short_config, tmp_path, capsys):
    code = main(["run", str(short_config), "--method", "plain-shooting", "--stance", "tracking",
                 "--out", str(tmp_path / "o"), "--quiet"])
    assert code == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "solver.stance" in err[0] and "'tracking'" in err[0] and "multiple-shooting" in err[0]
    assert not (tmp_path / "o").exists()
