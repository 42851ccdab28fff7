"""The human-likeness figures and the gait profile score (klaw_ocp.human_gait, docs/human-gait.md)."""
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.human_gait import (CYCLE_PERCENT, GPS_VARIABLES, dimensionless_speed, normative_curves,
                                 normative_table)


def test_the_normative_table_has_five_speed_classes_of_whole_cycles():
    table = normative_table()
    assert list(table) == ["VerySlow", "Slow", "Free", "Fast", "VeryFast"]
    speeds = [c["v_star"] for c in table.values()]
    assert speeds == sorted(speeds)
    for c in table.values():
        for column in ("pelvic_tilt", "hip_flexion", "knee_flexion", "ankle_dorsiflexion", "thigh"):
            assert c[column].shape == CYCLE_PERCENT.shape
        # a cycle is periodic: its ends agree within the subjects' spread
        assert abs(c["knee_flexion"][0] - c["knee_flexion"][-1]) < 2
        # the pattern of people: the knee nearly straight in terminal stance, 45-61° in swing (very slow to very fast)
        assert c["knee_flexion"][18:23].min() < 10 and 40 < c["knee_flexion"].max() < 65


def test_the_normative_curves_are_linear_in_the_dimensionless_speed_and_held_at_the_ends():
    table = normative_table()
    free, fast = table["Free"], table["Fast"]
    mid = normative_curves(0.5 * (free["v_star"] + fast["v_star"]))
    np.testing.assert_allclose(mid["knee"][0], 0.5 * (free["knee_flexion"] + fast["knee_flexion"]))
    np.testing.assert_allclose(normative_curves(5.0)["ankle"][0], table["VeryFast"]["ankle_dorsiflexion"])
    np.testing.assert_allclose(normative_curves(0.0)["thigh"][0],
                               table["VerySlow"]["hip_flexion"] - table["VerySlow"]["pelvic_tilt"])


def test_the_dimensionless_speed_of_the_natural_walk():
    body = Body(height=1.8, mass=80)
    assert dimensionless_speed(body, 5.0) == pytest.approx(5 / 3.6 / math.sqrt(body.g * (body.l1 + body.l9)))
    assert 0.43 < dimensionless_speed(body, 5.0) < 0.56          # between the free and fast classes
