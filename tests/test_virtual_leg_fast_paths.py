"""The virtual leg's shortcuts of issue #38 (the step's stance rules and double support) give the
same feet and numbers as what they replaced: ``virtual_leg._replace`` is ``dataclasses.replace``,
the knee's schedule of one sample on floats is the array one's, and the few hips' reach pitch
(its band roots in lists, up to ``heel_up_roots._FEW`` hips) is the array path's to the bit."""
import math
from dataclasses import replace

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.gait.attributes import LocomotionAttributes
from klaw_ocp.kinematics import heel_up_roots
from klaw_ocp.kinematics.leg_geometry import FlatFoot
from klaw_ocp.kinematics.pitch_rules import _knee_float
from klaw_ocp.kinematics.virtual_leg import StanceFoot, _replace

ATTRS = LocomotionAttributes.defaults()
BODY = Body(1.8, 80)


def _foot(rng) -> StanceFoot:
    t_step = rng.uniform(0.3, 0.7)
    hip = np.array([rng.uniform(-0.3, 0.0), 0.9 * BODY.l1])
    return StanceFoot.at_heel_strike(BODY, ATTRS, 0.2, hip, t_step, (rng.uniform(0.8, 1.5), 0.0))


def test_the_quick_replace_is_dataclasses_replace():
    rng = np.random.default_rng(3)
    for _ in range(20):
        foot = _foot(rng)
        changes = {"t_heel_off": rng.uniform(0, 0.5), "single_t": (0.1, 0.2), "single_deficit": (0.0, 0.01),
                   "knee_toe_off": rng.uniform(0.3, 0.8)}
        quick, slow = _replace(foot, **changes), replace(foot, **changes)
        assert type(quick) is StanceFoot and quick == slow and hash(quick) == hash(slow)
        assert quick.__dict__ == slow.__dict__ and foot != quick


def test_one_samples_knee_schedule_on_floats_is_the_arrays():
    rng = np.random.default_rng(4)
    for _ in range(50):
        foot = _foot(rng)
        if rng.random() < 0.5:
            foot = replace(foot, knee_hold=rng.uniform(0.0, 0.3), t_hold=rng.uniform(0.1, foot.t_step))
        for t in rng.uniform(-0.1, 1.0, 20).tolist():
            assert _knee_float(t, foot._rules()) == float(foot.knee_schedule(np.array([t]))[0])


@pytest.mark.parametrize("limit", (math.radians(ATTRS.meta_off_theta6), 0.2))
def test_many_few_hips_reach_pitch_is_the_arrays(monkeypatch, limit):
    """6 to 32 hips, many of them about meta-off (the band's roots of several hips stepped together)."""
    rng, foot = np.random.default_rng(5), FlatFoot(BODY, 0.3)
    head = 0.3 + BODY.metatarsal_reach
    for _ in range(100):
        n = int(rng.integers(6, heel_up_roots._FEW + 1))
        r, a = rng.uniform(0.85, 1.35, n), rng.uniform(-0.5, 1.0, n)
        hips = np.column_stack([head + r * BODY.l1 * np.sin(a), r * BODY.l1 * np.cos(a)])
        radius = BODY.l1 * rng.uniform(0.85, 1.0, n)
        few = heel_up_roots.reach_pitch(foot, limit, hips, radius)
        with monkeypatch.context() as patch:
            patch.setattr(heel_up_roots, "_FEW", 0)
            arrays = heel_up_roots.reach_pitch(foot, limit, hips, radius)
        assert np.array_equal(few, arrays)
