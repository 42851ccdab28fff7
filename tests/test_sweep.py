"""``klaw-ocp sweep``: --vary parsing, validation before any walk, the files, failures, executors."""
import csv
import math
import re

import pytest
import yaml

from klaw_ocp import sweep
from klaw_ocp.cli import main
from klaw_ocp.errors import ConfigError, ConvergenceError

HEADER = ["walk.speed", "method", "status", "failed_step", "failed_subphase", "residual", "steps", "iterations",
          "wall_s", "build_s", "compile_s", "max_subphase_s", "mean_speed_kmh", "hip_excursion_m", "peak_F_w", "peak_F_theta1", "peak_F_theta2",
          "peak_pa", "peak_F_theta3", "peak_F_theta4", "fallbacks", "message"]
NUMERIC = HEADER[5:20]
SHORT = {"name": "short", "body": {"height": 1.8, "mass": 80},
         "walk": {"speed": 5.0, "steps": 2}, "solver": {"method": "plain-shooting"}}


def _write_config(folder, data=SHORT):
    path = folder / "short.yaml"
    path.write_text(yaml.safe_dump(data))
    return path


@pytest.fixture
def short_config(tmp_path):
    return _write_config(tmp_path)


def _read(path):
    with open(path, newline="") as handle:
        return list(csv.reader(handle))


TIMINGS = ("wall_s", "build_s", "compile_s", "max_subphase_s")


#: result columns compared as numbers: what the walk measured (the residual is separate)
MEASURED = ("mean_speed_kmh", "hip_excursion_m", "peak_F_w", "peak_F_theta1", "peak_F_theta2", "peak_pa",
            "peak_F_theta3", "peak_F_theta4")


def _assert_same_rows(table, expected):
    """The sweep's rows are the reference rows, the same walks in the same order.

    Text (the varied value as given, method, status, the failure columns, fallbacks, message)
    and the number of steps must match exactly. Numbers are compared as numbers: a worker may
    run on another CPU (or load a BLAS tuned for another core), which changes round-off (~1e-16
    relative) that the solvers, stopping at |residual| < 1e-10, carry into the walk at about
    tolerance x conditioning (~1e-9 relative). So the measured columns agree to 1e-7 relative
    (another walk differs by 1e-3 and more; even 1e-3 N on a 1100 N peak force is 9e-7); the residual,
    itself round-off below the acceptance threshold 1e-9 of the solvers, to 1e-9 absolute; the
    iterations, which a residual that round-off moves across the tolerance may change by one per
    solve, to one per subphase (four per step). The timing columns differ from run to run.
    """
    assert table[0] == expected[0] == HEADER
    assert len(table) == len(expected), "one row per walk, none missing, none extra"
    for got, want in zip(table[1:], expected[1:]):
        got, want = dict(zip(HEADER, got)), dict(zip(HEADER, want))
        label = (want["walk.speed"], want["method"])
        for column in HEADER:
            if column in TIMINGS:
                assert (got[column] == "") == (want[column] == ""), (label, column)
            elif column in MEASURED:
                assert (got[column] == "") == (want[column] == ""), (label, column)
                if want[column]:
                    value = pytest.approx(float(want[column]), rel=1e-7, abs=1e-12)
                    assert float(got[column]) == value, (label, column)
            elif column == "residual" and want[column]:
                assert got[column] and abs(float(got[column]) - float(want[column])) <= 1e-9, (label, column)
            elif column == "iterations" and want[column]:
                assert abs(int(got[column]) - int(want[column])) <= 4 * int(want["steps"]), (label, column)
            else:
                assert got[column] == want[column], (label, column)


@pytest.fixture(scope="module")
def reference(tmp_path_factory):
    """walk.speed=4,5 with plain shooting in this process: sweep.csv's rows."""
    folder = tmp_path_factory.mktemp("reference")
    config = _write_config(folder)
    assert main(["sweep", str(config), "--vary", "walk.speed=4,5", "--workers", "1", "--quiet",
                 "--out", str(folder / "out")]) == 0
    return config, _read(folder / "out" / "sweep.csv")


# ------------------------------------------------------------------------------------ parsing

@pytest.mark.parametrize("text, expected", [
    ("1,3,5", [1, 3, 5]),
    ("true,false", [True, False]),
    ("0:1:0.3", [0, 0.3, 0.6, 0.9]),
    ("0.1:0.3:0.1", [0.1, 0.2, 0.3]),
    ("1:5:2", [1, 3, 5]),
    ("1,2:4:1, 7.5", [1, 2, 3, 4, 7.5]),
    ("null,0.7", [None, 0.7]),
    ("1e-3", [0.001]),
    ("multiple-shooting", ["multiple-shooting"]),
])
def test_values(text, expected):
    assert sweep.parse_values(text) == expected


def test_inclusive_range():
    values = sweep.parse_values("0.5:8:0.5")
    assert len(values) == 16 and values[0] == 0.5 and values[-1] == 8.0
    assert sweep.parse_values("0:1:0.3")[-1] == 0.9                      # 1 is not on the grid
    assert [type(v) for v in sweep.parse_values("10:30:10")] == [int] * 3  # solver.intervals stays int
    assert sweep.parse_vary("walk.speed=1,3,5") == ("walk.speed", [1, 3, 5])


@pytest.mark.parametrize("vary", ["walk.speed", "walk.speed=", "walk.speed=1,,2", "walk.speed=1,", "=1,2",
                                  "walk..speed=1", "walk.speed=1:2:0", "walk.speed=1:2:-1", "walk.speed=2:1:0.5",
                                  "walk.speed=1:2", "walk.speed=a:b:c", "walk.speed=[1,2]",
                                  "walk.speed=0.5:8:0.0001"])
def test_bad_vary_exits_2_with_one_line(vary, short_config, tmp_path, capsys):
    assert main(["sweep", str(short_config), "--vary", vary, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: --vary") and "Traceback" not in err[0]
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("args, words", [
    (["--vary", "walk.speed=1:9:0.01", "--vary", "body.height=1.5:2:0.01"], ["--vary", "walk"]),
    (["--vary", "walk.speed=1", "--vary", "walk.speed=2"], ["twice"]),
    (["--vary", "walk.speed=4", "--workers", "0"], ["--workers"]),
    (["--vary", "walk.speed.x=1"], ["mappings"]),
])
def test_bad_sweep_arguments_exit_2(args, words, short_config, tmp_path, capsys):
    assert main(["sweep", str(short_config), *args, "--out", str(tmp_path / "o"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and all(w in err[0] for w in words)
    assert not (tmp_path / "o").exists()


def test_help(capsys):
    assert main(["sweep", "--help"]) == 0
    out = capsys.readouterr().out
    assert "--vary" in out and "--scheduler" in out and "start:stop:step" in out


# ---------------------------------------------------------------------------- grid, validation

def test_invalid_combination_is_refused_before_any_walk(short_config, tmp_path, capsys, monkeypatch):
    ran = []
    monkeypatch.setattr(sweep, "run_walk", lambda *args: ran.append(args))
    out = tmp_path / "o"
    assert main(["sweep", str(short_config), "--vary", "walk.speed=5,50", "--vary", "walk.start_from_rest=true,false",
                 "--workers", "1", "--out", str(out)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "walk.speed=50, walk.start_from_rest=true: walk.speed: got 50" in err[0]
    assert ran == [] and not out.exists()


def test_grid_order_paths_and_methods():
    base = {k: v for k, v in SHORT.items() if k != "solver"}
    name, tasks = sweep.expand(base, {"walk.speed": [4, 5], "attributes.pelvic_list": [3.0, 5.0]}, "both")
    assert name == "short" and len(tasks) == 8
    assert [(t["values"]["walk.speed"], t["values"]["attributes.pelvic_list"], t["method"]) for t in tasks[:3]] == [
        (4, 3.0, "multiple-shooting"), (4, 3.0, "plain-shooting"), (4, 5.0, "multiple-shooting")]
    assert tasks[0]["mapping"]["attributes"] == {"pelvic_list": 3.0}   # created on the way
    assert "attributes" not in base                                      # the base is not touched
    _, tasks = sweep.expand(base, {"solver.method": ["plain-shooting", "multiple-shooting"]})
    assert [t["method"] for t in tasks] == ["plain-shooting", "multiple-shooting"]  # the config's method


def test_tracking_stance_with_plain_shooting_is_refused_up_front():
    data = {**SHORT, "solver": {"stance": "tracking"}}
    with pytest.raises(ConfigError, match=r"walk.speed=4: solver.stance"):
        sweep.expand(data, {"walk.speed": [4]}, "both")


# ------------------------------------------------------------------------------------ the files

def test_end_to_end_both_methods(short_config, tmp_path, capsys):
    out = tmp_path / "o"
    code = main(["sweep", str(short_config), "--vary", "walk.speed=4,5", "--method", "both", "--workers", "1",
                 "--out", str(out), "--quiet"])
    printed = capsys.readouterr().out.strip().splitlines()
    assert code == 0
    assert printed == [f"4 walks: 4 ok, 0 failed, 0 error; wrote {out / 'sweep.csv'} and {out / 'sweep.png'}"]
    table = _read(out / "sweep.csv")
    assert table[0] == HEADER and len(table) == 5
    rows = [dict(zip(HEADER, r)) for r in table[1:]]
    assert [(r["walk.speed"], r["method"]) for r in rows] == [
        ("4", "multiple-shooting"), ("4", "plain-shooting"), ("5", "multiple-shooting"), ("5", "plain-shooting")]
    for r in rows:
        assert r["status"] == "ok" and r["steps"] == "2" and r["failed_step"] == r["message"] == ""
        assert all(math.isfinite(float(r[c])) for c in NUMERIC)
        assert float(r["residual"]) < 1e-6 and int(r["iterations"]) > 0 and float(r["peak_F_w"]) > 0
        assert float(r["mean_speed_kmh"]) == pytest.approx(float(r["walk.speed"]), abs=0.05)
        assert 0 < float(r["hip_excursion_m"]) < 0.2
    assert (out / "sweep.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_failures_are_rows_and_do_not_stop_the_sweep(short_config, tmp_path, capsys, monkeypatch):
    from klaw_ocp.control.step import StepController
    original = StepController.solve_step

    def flaky(self, plan, inp, k, *args, **kwargs):
        speed = plan.parameters.speed_kmh
        if k == 1 and abs(speed - 4.0) < 1e-9:
            raise ConvergenceError(1, "swing2", 0.031, "forced for the test")
        if abs(speed - 4.5) < 1e-9:
            raise RuntimeError("boom\nsecond line")
        return original(self, plan, inp, k, *args, **kwargs)

    monkeypatch.setattr(StepController, "solve_step", flaky)
    out = tmp_path / "o"
    assert main(["sweep", str(short_config), "--vary", "walk.speed=4:5:0.5", "--workers", "1", "--out", str(out),
                 "--quiet"]) == 3
    assert capsys.readouterr().out.startswith("3 walks: 1 ok, 1 failed, 1 error;")
    table = _read(out / "sweep.csv")
    failed, error, ok = (dict(zip(HEADER, r)) for r in table[1:])
    assert (failed["walk.speed"], failed["status"], failed["failed_step"], failed["failed_subphase"]) == (
        "4.0", "failed", "1", "swing2")
    assert float(failed["residual"]) == 0.031 and failed["steps"] == "1" and "step 1" in failed["message"]
    assert float(failed["peak_F_w"]) > 0                                  # from the completed step
    assert error["status"] == "error" and error["message"] == "RuntimeError: boom second line"
    assert error["failed_step"] == error["residual"] == ""
    assert ok["status"] == "ok" and ok["steps"] == "2"
    assert (out / "sweep.png").exists()


def test_sweep_csv_grows_by_appended_lines_while_the_walks_run(short_config, tmp_path, monkeypatch):
    """Each finished walk adds its line to the staging folder's sweep.csv, the file appended to
    and not written again: a walk sees the header and the lines of the walks before it."""
    out, seen = tmp_path / "o", []

    def quick(mapping, method):
        staging = list(tmp_path.glob("o.partial-*"))
        path = staging[0] / "sweep.csv" if staging else None
        seen.append((path.stat().st_ino, path.read_text()) if path is not None and path.is_file() else None)
        return {**dict.fromkeys(sweep.RESULT_COLUMNS), "method": method, "status": "ok", "steps": 2,
                "wall_s": 0.5, "iterations": 3}
    monkeypatch.setattr(sweep, "run_walk", quick)
    assert main(["sweep", str(short_config), "--vary", "walk.speed=3,4,5", "--workers", "1", "--out", str(out),
                 "--quiet"]) == 0
    assert seen[0] is None and seen[1][0] == seen[2][0]           # one file, appended to
    assert seen[1][1].count("\n") == 2 and seen[2][1].startswith(seen[1][1]) and seen[2][1].count("\n") == 3
    final = (out / "sweep.csv").read_text()
    assert final.startswith(seen[2][1]) and final.count("\n") == 4


def test_fallbacks_column_reads_the_summary(monkeypatch):
    import klaw_ocp.results as results
    original = results.walk_summary

    def with_fallbacks(walk, *args, **kwargs):
        summary = original(walk, *args, **kwargs)
        summary["steps"][1]["subphases"][2]["fallbacks"] = ["ipopt", "smaller-step"]
        return summary

    own = sweep.run_walk(SHORT, "plain-shooting")["fallbacks"]   # what the walk itself needed
    monkeypatch.setattr(results, "walk_summary", with_fallbacks)
    row = sweep.run_walk(SHORT, "plain-shooting")
    injected = "step1.swing2:ipopt;step1.swing2:smaller-step"
    # the injected list replaces step 1's swing2 entries; the walk's other fallbacks stay
    kept = [f for f in own.split(";") if f and not f.startswith("step1.swing2:")]
    assert row["status"] == "ok" and injected in row["fallbacks"]
    assert sorted(row["fallbacks"].split(";")) == sorted(kept + injected.split(";"))
    assert all(re.fullmatch(r"step\d+\.(stance|swing[123]):[a-z-]+", f) for f in row["fallbacks"].split(";"))


def test_map_with_three_paths_and_categories(tmp_path, monkeypatch):
    """Speed on x (numeric), start_from_rest on y (categorical), aggregated over body.height: one
    panel per method, four cells of two walks each; the (3, true) cell holds the failed walk."""
    import matplotlib.image as mpimg
    import numpy as np
    from matplotlib import colormaps
    from matplotlib.colors import to_rgb

    from klaw_ocp.figures import sweep_plot
    rows = [{"walk.speed": v, "walk.start_from_rest": r, "body.height": h, "method": m,
             "status": "failed" if (v, r, h) == (3, True, 1.7) else "ok", "wall_s": v + (1.5 if h == 1.8 else 1.0),
             "failed_step": 0, "failed_subphase": "stance"}
            for v in (1, 3) for r in (True, False) for h in (1.7, 1.8) for m in sweep.METHODS]
    paths = ["walk.speed", "walk.start_from_rest", "body.height"]
    # the data the map is drawn from: per method, four cells of two walks (the two heights), the
    # larger wall time of the two
    for method in sweep.METHODS:
        cells = sweep_plot._cells([r for r in rows if r["method"] == method], paths[0], paths[1])
        assert {k: (c["ok"], c["wall"], c["n"]) for k, c in cells.items()} == {
            ("1", "true"): (True, 2.5, 2), ("1", "false"): (True, 2.5, 2),
            ("3", "true"): (False, 4.5, 2), ("3", "false"): (True, 4.5, 2)}
        assert cells[("3", "true")]["row"]["body.height"] == 1.7
    figures = []
    figure = sweep_plot.sweep_figure

    def keep(*args, **kwargs):
        figures.append(figure(*args, **kwargs))
        return figures[-1]
    monkeypatch.setattr(sweep_plot, "sweep_figure", keep)
    path = sweep_plot.write_sweep_png(rows, paths, tmp_path / "m.png")
    (fig,) = figures                       # the figure that was saved (drawn, so laid out)
    assert "16 walks, 14 ok, 2 failed, 0 error" in fig._suptitle.get_text()
    assert "aggregated over body.height" in fig._suptitle.get_text()
    panels = [ax for ax in fig.axes if ax.get_title()]
    assert [ax.get_title() for ax in panels] == [f"{m}: 6/8 ok" for m in sweep.METHODS]
    assert [t.get_text() for t in panels[0].get_yticklabels()] == ["true", "false"]   # grid order
    # the image written is the figure: its size, and the cells' colours where the cells are
    image = mpimg.imread(path)
    width, height = (sweep_plot._PANEL_IN * len(sweep.METHODS) + 1.4) * sweep_plot._DPI, 4.4 * sweep_plot._DPI
    assert image.shape[:2] == (round(height), round(width))
    assert len(np.unique(image[..., :3].reshape(-1, 3), axis=0)) > 50, "not a blank image"
    viridis = colormaps["viridis"]
    expected = {(1.0, 0.0): viridis(0.0), (1.0, 1.0): viridis(0.0), (3.0, 1.0): viridis(1.0),   # 2.5 s, 4.5 s
                (3.0, 0.0): sweep_plot._FAIL_COLOUR}                                              # the 'x'
    for ax in panels:
        assert [t.get_text() for t in ax.get_xticklabels()] == ["1", "3"]
        offsets = sorted(tuple(xy) for c in ax.collections for xy in c.get_offsets())
        assert offsets == sorted(expected)
        assert [t.get_text() for t in ax.texts] == ["step 0\nstance"]    # the failed walk's label
        for (x, y), colour in expected.items():
            px, py = ax.transData.transform((x, y))
            pixel = image[int(np.rint(height - py)), int(np.rint(px)), :3]   # rows count from the top
            np.testing.assert_allclose(pixel, to_rgb(colour), atol=0.02, err_msg=f"{ax.get_title()} ({x}, {y})")


# ------------------------------------------------------------------------------------ executors

def test_process_pool_gives_the_same_rows(reference, tmp_path):
    config, expected = reference
    assert main(["sweep", str(config), "--vary", "walk.speed=4,5", "--workers", "2", "--quiet",
                 "--out", str(tmp_path / "o")]) == 0
    _assert_same_rows(_read(tmp_path / "o" / "sweep.csv"), expected)


def test_dask_cluster_gives_the_same_rows(reference, tmp_path):
    distributed = pytest.importorskip("distributed")
    config, expected = reference
    with distributed.LocalCluster(n_workers=2, processes=True, threads_per_worker=1,
                                  dashboard_address=None) as cluster:
        assert main(["sweep", str(config), "--vary", "walk.speed=4,5", "--scheduler", cluster.scheduler_address,
                     "--quiet", "--out", str(tmp_path / "o")]) == 0
    _assert_same_rows(_read(tmp_path / "o" / "sweep.csv"), expected)


def test_missing_dask_is_one_line(short_config, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(__import__("sys").modules, "distributed", None)   # import distributed -> ImportError
    assert main(["sweep", str(short_config), "--vary", "walk.speed=4", "--scheduler", "tcp://127.0.0.1:8786",
                 "--quiet", "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and 'pip install -e ".[cluster]"' in err[0]
