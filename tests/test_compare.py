"""Comparing finished runs (klaw_ocp.compare, klaw_ocp.figures.compare_plot): rows, statistics, figure.

The natural walk is simulated once in each solver mode; the rows and statistics are checked
against the two walks' own results, computed here independently of klaw_ocp.compare.
"""
import io
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from klaw_ocp.compare import (SUBPHASES, comparison_csv, comparison_rows, comparison_stats, comparison_table,
                              unique_labels)
from klaw_ocp.result_files import write_walk
from klaw_ocp.result_files.run_data import RunData
from klaw_ocp.walk import simulate_walk

ROOT = Path(__file__).resolve().parents[1]
METHODS = ("multiple-shooting", "plain-shooting")


@pytest.fixture(scope="module")
def walks():
    return {m: simulate_walk(ROOT / "configs" / "natural_walk.yaml", method=m) for m in METHODS}


@pytest.fixture(scope="module")
def runs(walks):
    return [RunData.from_walk(walks[m]) for m in METHODS]


@pytest.fixture(scope="module")
def short_long():
    return [RunData.from_walk(simulate_walk(ROOT / "configs" / f"{name}.yaml", method="multiple-shooting"))
            for name in ("short_steps", "long_steps")]


def _diff_columns(row):
    return {k: v for k, v in row.items() if k.startswith("d_")}


def test_one_row_per_step_subphase_and_run_in_that_order(runs, walks):
    rows = comparison_rows(runs)
    n_steps = len(walks["multiple-shooting"].steps)
    assert n_steps == 22
    assert len(rows) == n_steps * len(SUBPHASES) * len(runs)
    labels = unique_labels(runs)
    expected = [(k, name, label) for k in range(n_steps) for name in SUBPHASES for label in labels]
    assert [(r["step"], r["subphase"], r["run"]) for r in rows] == expected
    assert len({tuple(r) for r in rows}) == 1          # every row has every column, in one order
    assert {"F_theta1_magnitude [N m]", "pa_offset [m]", "d_F_theta3_moment [N m]", "residual", "iterations",
            "solve_s", "nlp", "fallbacks"} <= set(rows[0])


def test_parameter_differences_equal_the_walks_own_differences(runs, walks):
    rows = comparison_rows(runs)
    first, second = (walks[m] for m in METHODS)
    label = unique_labels(runs)[1]
    checked = 0
    for row in rows:
        if row["run"] != label:
            assert all(v is None for v in _diff_columns(row).values())   # the first run: empty
            continue
        a = first.steps[row["step"]].subphase(row["subphase"]).parameters
        b = second.steps[row["step"]].subphase(row["subphase"]).parameters
        for column, value in _diff_columns(row).items():
            name = column[2:].split(" [")[0]
            if name in b:
                assert value == pytest.approx(float(b[name]) - float(a[name]), rel=1e-12, abs=1e-15)
                checked += 1
            else:
                assert value is None
    assert checked > 0


def test_absent_parameters_are_empty_cells(runs):
    rows = comparison_rows(runs)
    swing1 = next(r for r in rows if r["subphase"] == "swing1")
    assert swing1["F_theta1_magnitude [N m]"] is None
    assert isinstance(swing1["F_theta3_mean [N m]"], float)
    text = comparison_csv(rows)
    header, line = text.splitlines()[:2]
    assert header.split(",")[:4] == ["run", "step", "subphase", "F_theta1_magnitude [N m]"]
    assert line.count(",,") > 0


def test_hip_height_difference_equals_the_direct_maximum(runs, walks):
    from klaw_ocp.results import walk_table
    a, b = (walk_table(walks[m]) for m in METHODS)
    direct = float(np.max(np.abs(a["hip_y"] - b["hip_y"])))
    stats = comparison_stats(runs)
    other = stats["runs"][1]
    assert other["grid"] == "identical"
    assert other["hip_y"]["value"] == pytest.approx(direct, rel=1e-12, abs=0.0)
    assert 0 < direct < 1e-6                                      # the two modes agree closely
    for column in ("w", "theta1", "theta2", "theta3", "theta4"):
        assert other["angles"][column]["value"] == pytest.approx(
            float(np.nanmax(np.abs(a[column] - b[column]))), rel=1e-12)
    assert set(other["parameters"]) == set(SUBPHASES)
    assert stats["runs"][0]["hip_y"] is None
    for entry, walk in zip(stats["runs"], (walks[m] for m in METHODS)):
        subs = [s for step in walk.steps for s in step.subphases]
        assert entry["steps"] == len(walk.steps)
        assert entry["iterations"] == sum(int(s.iterations) for s in subs)
        assert entry["solve_s"] == pytest.approx(sum(float(s.wall_s) for s in subs))
    table = comparison_table(stats)
    assert "max |Δ hip height|" in table and "iterations (sum)" in table and "run 2:" in table


def _same(x, y) -> bool:
    if isinstance(x, float) and isinstance(y, float):
        return x == y or math.isclose(x, y, rel_tol=1e-12, abs_tol=0.0)
    return x == y


def test_rows_from_folders_equal_rows_from_walks(runs, walks, tmp_path):
    folders = []
    for k, method in enumerate(METHODS):
        write_walk(walks[method], tmp_path / str(k))
        folders.append(RunData.from_folder(tmp_path / str(k)))
    from_walks, from_folders = comparison_rows(runs), comparison_rows(folders)
    assert len(from_walks) == len(from_folders)
    for a, b in zip(from_walks, from_folders):
        assert list(a) == list(b)
        assert all(_same(a[c], b[c]) for c in a), [c for c in a if not _same(a[c], b[c])]
    sa, sb = comparison_stats(runs)["runs"][1], comparison_stats(folders)["runs"][1]
    assert sa["hip_y"]["value"] == pytest.approx(sb["hip_y"]["value"], rel=1e-9)


def test_equal_labels_are_made_unique(runs):
    labels = unique_labels([runs[0], runs[0], runs[1]])
    assert labels[1] == labels[0] + " #2" and len(set(labels)) == 3
    rows = comparison_rows([runs[0], runs[0]])
    assert {r["run"] for r in rows} == set(unique_labels([runs[0], runs[0]]))
    assert all(v == 0.0 for r in rows[1::2] for v in _diff_columns(r).values() if v is not None)


def test_different_configs_compare_with_unmatched_steps_left_empty(short_long):
    short, long_ = short_long
    assert len(short.steps) != len(long_.steps)
    rows = comparison_rows([short, long_])
    assert len(rows) == (len(short.steps) + len(long_.steps)) * len(SUBPHASES)
    first_label, second_label = unique_labels([short, long_])
    matched = min(len(short.steps), len(long_.steps))
    for row in rows:
        diffs = _diff_columns(row).values()
        if row["run"] == first_label or row["step"] >= matched:
            assert all(v is None for v in diffs)
        else:
            assert any(v is not None for v in diffs)
    stats = comparison_stats([short, long_])["runs"][1]
    assert stats["grid"] == "interpolated" and "interpolated" in stats["grid_note"]
    assert math.isfinite(stats["hip_y"]["value"]) and stats["hip_y"]["value"] > 0
    assert stats["unmatched"] == 0 and stats["matched"] == matched * len(SUBPHASES)
    assert "interpolated" in comparison_table(comparison_stats([short, long_]))


@pytest.mark.parametrize("pair", ["modes", "configs"])
def test_figure_renders_a_non_blank_png(pair, runs, short_long):
    import matplotlib.image as mpimg

    from klaw_ocp.figures.compare_plot import comparison_figure
    from klaw_ocp.figures.plot_style import png_bytes
    image = mpimg.imread(io.BytesIO(png_bytes(comparison_figure(runs if pair == "modes" else short_long))), format="png")
    assert image.ndim == 3 and image.shape[0] > 1000 and image.shape[1] > 1000
    assert float(image[..., :3].std()) > 0.05                       # not a blank page


def test_comparison_imports_no_solver():
    code = ("import sys, klaw_ocp.compare, klaw_ocp.figures.compare_plot; "
            "print(any(m.startswith('klaw_ocp.solvers') for m in sys.modules))")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "False"
