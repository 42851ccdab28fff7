"""``klaw-ocp run`` writes the body (angles.csv, docs/body.md) and its plots, at ``output.fps``
(or ``--fps``) frames per second, and refuses a bad frame rate in one line before any solving;
``RunData`` reads angles.csv back, so ``klaw-ocp plot`` redraws the body's plots from files."""
import json
import math

import numpy as np
import pytest
import yaml

from klaw_ocp.body_motion.skeleton import ANGLE_NAMES
from klaw_ocp.cli import main
from klaw_ocp.result_files.run_data import RunData

COLUMNS = ["time", "root_x", "root_y", "root_z", *ANGLE_NAMES]
BODY_PLOTS = {"joint_angles.png", "body.png"}


def _header_and_rows(path):
    lines = path.read_text(encoding="utf-8").splitlines()
    return lines[0].split(","), np.array([[float(v) for v in line.split(",")] for line in lines[1:]])


def test_run_writes_angles_csv_at_every_frame_and_the_body_plots(short_config, tmp_path, capsys, monkeypatch):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--fps", "50"]) == 0
    assert "7 plots" in capsys.readouterr().out
    header, rows = _header_and_rows(out / "angles.csv")
    assert header == COLUMNS and len(COLUMNS) == 60
    summary = json.loads((out / "summary.json").read_text())
    frames = math.floor(summary["simulated_s"] * 50 + 1e-9) + 1
    np.testing.assert_allclose(rows[:, 0], np.arange(frames) / 50, rtol=1e-11, atol=1e-12)
    assert np.all(np.isfinite(rows)) and rows.shape == (frames, 60)
    assert BODY_PLOTS <= {p.name for p in (out / "plots").iterdir()}
    assert yaml.safe_load((out / "config.resolved.yaml").read_text())["output"]["fps"] == 50
    # read back: the same columns, and the plots redrawn from the files alone
    run = RunData.from_folder(out)
    assert list(run.angles) == COLUMNS and run.angles["time"].shape == (frames,)
    import klaw_ocp.walk
    monkeypatch.setattr(klaw_ocp.walk, "simulate_walk", lambda *a, **k: pytest.fail("solved"))
    redrawn = tmp_path / "redrawn"
    assert main(["plot", str(out), "--out", str(redrawn)]) == 0
    assert BODY_PLOTS <= {p.name for p in redrawn.iterdir()}


def test_the_angles_read_back_are_the_walks(short_config, tmp_path):
    """angles.csv holds the angles of the walk in memory to its 12 significant digits."""
    from klaw_ocp.config import load_config
    from klaw_ocp.walk import simulate_walk, walk_spec
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-plots"]) == 0
    from_folder = RunData.from_folder(out).angles
    from_walk = RunData.from_walk(simulate_walk(walk_spec(load_config(short_config))), fps=30.0).angles
    assert list(from_folder) == list(from_walk)
    for name in from_walk:
        np.testing.assert_allclose(from_folder[name], from_walk[name], rtol=1e-11, atol=1e-9, err_msg=name)


def test_output_fps_in_the_config_sets_the_frame_rate(short_config, tmp_path):
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-plots", "--set", "output.fps=12.5"]) == 0
    _, rows = _header_and_rows(out / "angles.csv")
    assert rows[1, 0] - rows[0, 0] == pytest.approx(1 / 12.5)


@pytest.mark.parametrize("value, allowed", [("0", "a number > 0"), ("-1", "a number > 0"),
                                            ('"abc"', "a number"), ("1001", "a number <= 1000")])
def test_a_bad_frame_rate_is_refused_in_one_line_before_solving(value, allowed, short_config, tmp_path, capsys,
                                                                no_solving):
    data = yaml.safe_load(short_config.read_text())
    data["output"] = {"fps": yaml.safe_load(value)}
    bad = tmp_path / "bad.yaml"
    bad.write_text(yaml.safe_dump(data))
    for argv in (["run", str(bad)], ["run", str(short_config), "--fps", value.strip('"')]):
        assert main([*argv, "--out", str(tmp_path / "o"), "--quiet"]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith("klaw-ocp: error: output.fps: got ") and allowed in err[0], err
        assert not (tmp_path / "o").exists()
