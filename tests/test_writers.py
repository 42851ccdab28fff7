"""Result files are written atomically with the user's normal file mode; summary.json is the json
module's; dynamics.csv, one format per row, is what the csv module writes; walk.bvh's and
walk.mot's rows are each value's fixed-decimal format, never "-0"."""
import csv
import io
import json
import math
import os

import numpy as np
import pytest


from klaw_ocp.result_files.atomic import atomic_write_bytes, atomic_write_text
from klaw_ocp.result_files.summary_json import summary_text
from klaw_ocp.result_files.tables import decimal_rows, dynamics_csv
from klaw_ocp.results import COLUMNS


def test_files_get_the_users_normal_mode_and_no_temporary_is_left(tmp_path):
    old = os.umask(0o022)
    try:
        atomic_write_text(tmp_path / "a" / "x.csv", "t,w\n0,1\n")
        atomic_write_bytes(tmp_path / "a" / "y.png", b"\x89PNG")
    finally:
        os.umask(old)
    assert (tmp_path / "a" / "x.csv").read_text() == "t,w\n0,1\n"
    assert (tmp_path / "a" / "y.png").read_bytes() == b"\x89PNG"
    assert {oct(p.stat().st_mode & 0o777) for p in (tmp_path / "a").iterdir()} == {"0o644"}
    assert sorted(p.name for p in (tmp_path / "a").iterdir()) == ["x.csv", "y.png"]



def test_the_summary_is_json_dumps_and_the_per_step_summary_its_compact_form():
    summary = {"name": "w", "x": [1.5, None, True], "steps": [{"a": 1}, {"b": [2.0]}]}
    assert summary_text(summary) == json.dumps(summary, indent=2, allow_nan=False) + "\n"
    steps = [json.dumps(step) for step in summary["steps"]]
    assert summary_text(summary, steps) == json.dumps(summary) + "\n"
    with pytest.raises(ValueError):
        summary_text({"x": math.nan})


def test_dynamics_csv_is_what_the_csv_module_writes():
    rng = np.random.default_rng(3)
    table = {c: rng.normal(size=5) for c in COLUMNS}
    table["step"] = np.array([0.0, 0.0, 1.0, 1.0, 2.0])
    table["subphase"] = np.array(["double_support", "swing1", "swing2", "swing3", "swing1"])
    table["F_theta3"][0] = math.nan
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(COLUMNS)
    writer.writerows(zip(*[table[c].tolist() if c == "subphase" else [int(v) for v in table[c]] if c == "step"
                           else [repr(v) for v in table[c].tolist()] for c in COLUMNS]))
    assert dynamics_csv(None, table) == buffer.getvalue()


def test_decimal_rows_round_first_and_write_no_minus_zero():
    values = np.array([[-1e-12, 0.1234567891234], [2.5, -3.0]])
    assert decimal_rows(values, 9, " ") == "0.000000000 0.123456789\n2.500000000 -3.000000000\n"
    assert decimal_rows(np.array([[1e7, -0.5], [np.inf, 1.0]]), 2, "\t") == "10000000.00\t-0.50\ninf\t1.00\n"
    assert decimal_rows(np.zeros((0, 3)), 9, " ") == ""


@pytest.mark.parametrize("x", [np.array([0.0, 0.1]), np.linspace(0.2, 0.6, 9), 0.3 + np.arange(7) * 0.01,
                               np.array([0.0, 0.013, 0.02, 0.061, 0.07, 0.1])])
def test_the_tables_knee_rates_are_numpys_gradient_bit_for_bit(x):
    """dynamics.csv's and the body's finite-difference rates (walk_samples.gradient): np.gradient's
    numbers."""
    from klaw_ocp.body_motion.walk_samples import gradient
    f = np.sin(7 * x) + x ** 3
    np.testing.assert_array_max_ulp(gradient(f, x), np.gradient(f, x), maxulp=1)   # a numpy release may reorder
