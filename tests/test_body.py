"""Appendix B, Table B-1: the anthropometry example and the validated ranges."""
import math

import pytest

from klaw_ocp.body import Body
from klaw_ocp.errors import ConfigError


def test_thigh_example_of_appendix_b():
    b = Body(height=1.8, mass=80)
    assert b.m3 == pytest.approx(8.0)
    assert b.l3 == pytest.approx(0.426, abs=5e-4)
    assert b.r3 == pytest.approx(0.184, abs=5e-4)
    # ERRATA 5: I = m (gamma l)^2, not the printed m (l r)^2 = 0.0276
    assert b.I3 == pytest.approx(0.1515, abs=1e-4)
    assert b.gamma3 == pytest.approx(0.138, abs=5e-4)


def test_derived_segments_and_gravity():
    b = Body(1.8, 80)
    assert b.l1 == pytest.approx(b.l3 + b.l4)
    assert b.l1 == pytest.approx(0.86805, abs=1e-9)
    assert b.m1 == pytest.approx(b.m3 + b.m4)
    assert b.r1 == pytest.approx(0.553 * b.l1)
    assert b.g == 9.81
    assert math.cos(b.omega8) == pytest.approx(b.l8 / b.l11)


def test_lengths_scale_with_height_masses_with_mass():
    a, b = Body(1.5, 60), Body(1.8, 90)
    assert b.l9 / a.l9 == pytest.approx(1.8 / 1.5)
    assert b.m2 / a.m2 == pytest.approx(1.5)


@pytest.mark.parametrize("height, mass, field", [
    (0, 80, "body.height"), (-1.8, 80, "body.height"), (float("nan"), 80, "body.height"),
    (float("inf"), 80, "body.height"), (3.5, 80, "body.height"), (True, 80, "body.height"),
    ("1.8", 80, "body.height"), (1.8, 0, "body.mass"), (1.8, 1000, "body.mass"),
])
def test_bad_body_is_rejected_with_field_and_value(height, mass, field):
    with pytest.raises(ConfigError) as err:
        Body(height=height, mass=mass)
    msg = str(err.value)
    assert msg.startswith(f"{field}: got ")
    assert "allowed" in msg and "\n" not in msg
