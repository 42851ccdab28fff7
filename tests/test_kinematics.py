"""Forward kinematics: the kinematic foot (figures 5-6, Table B-1 rows 8-13), the swing leg and the
stance hip / upper body."""
from __future__ import annotations

import casadi as ca
import numpy as np
import pytest

from _dynamics_support import BODIES
from klaw_ocp.dynamics import (foot_points, foot_points_sx, stance_hip, swing_functions, swing_leg_points,
                               upper_body_com)
from klaw_ocp.errors import ConfigError

TOL = 1e-12


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_neutral_foot_on_flat_ground(body):
    """Vertical shank, theta5 = 90 deg, ankle at (0, l9): heel (-l8, 0), sole and toe tip on y = 0."""
    pts = foot_points(body, [0.0, body.l9], 0.0, np.pi / 2)
    np.testing.assert_allclose(pts["heel"], [-body.l8, 0.0], atol=TOL)
    np.testing.assert_allclose(pts["metatarsal"], [np.sqrt(body.l12 ** 2 - body.l9 ** 2), 0.0], atol=TOL)
    np.testing.assert_allclose(pts["toe"], [np.sqrt(body.l12 ** 2 - body.l9 ** 2) + body.l13, 0.0], atol=TOL)


def test_foot_distances_and_toe_dorsiflexion():
    """Heel-ankle = l11, ankle-metatarsal = l12, metatarsal-toe = l13 in any pose; the angle
    knee-ankle-heel is theta5 + omega8 (the interior angle of eq. 3); theta6 > 0 lifts the toe
    relative to the sole; theta5 < 90 deg is plantar flexion (toe down, heel up)."""
    body = BODIES[0]
    rng = np.random.default_rng(11)
    for ankle, phi, t5, t6 in zip(rng.uniform(-1, 1, (20, 2)), rng.uniform(-1, 1, 20),
                                  rng.uniform(1.0, 2.2, 20), rng.uniform(0, 0.8, 20)):
        pts = foot_points(body, ankle, phi, t5, t6)
        # heel-ankle is sqrt(l8^2 + l9^2), which is Table B-1's l11 to the table's 4 digits
        assert abs(np.linalg.norm(pts["heel"] - ankle) - np.hypot(body.l8, body.l9)) < TOL
        assert abs(np.linalg.norm(pts["heel"] - ankle) / body.l11 - 1) < 2e-4
        assert abs(np.linalg.norm(pts["metatarsal"] - ankle) - body.l12) < TOL
        assert abs(np.linalg.norm(pts["toe"] - pts["metatarsal"]) - body.l13) < TOL
        to_knee, to_heel = np.array([np.sin(phi), np.cos(phi)]), pts["heel"] - ankle
        angle = np.arccos(to_knee @ to_heel / np.linalg.norm(to_heel))
        omega8 = np.arctan2(body.l9, body.l8)  # exact for this geometry; Body.omega8 uses rounded l11
        assert abs(angle - (t5 + omega8)) < 1e-9
        assert abs(omega8 - body.omega8) < 1e-3
    flat = foot_points(body, [0.0, body.l9], 0.0, np.pi / 2)
    lifted = foot_points(body, [0.0, body.l9], 0.0, np.pi / 2, 0.4)
    plantar = foot_points(body, [0.0, body.l9], 0.0, np.pi / 2 - 0.3)
    assert lifted["toe"][1] > flat["toe"][1] + 0.01
    assert plantar["toe"][1] < flat["toe"][1] - 0.01 and plantar["heel"][1] > 0.0


def test_foot_points_sx_is_symbolic():
    body = BODIES[0]
    ankle, phi, t5, t6 = ca.SX.sym("ankle", 2), ca.SX.sym("phi"), ca.SX.sym("t5"), ca.SX.sym("t6")
    pts = foot_points_sx(ankle, phi, t5, t6, body.l8, body.l9, body.l12, body.l13)
    fn = ca.Function("foot", [ankle, phi, t5, t6], [pts["heel"], pts["toe"]])
    heel, toe = fn([0.3, 0.2], -0.2, 1.7, 0.1)
    ref = foot_points(body, [0.3, 0.2], -0.2, 1.7, 0.1)
    np.testing.assert_allclose(np.asarray(heel).ravel(), ref["heel"], atol=TOL)
    np.testing.assert_allclose(np.asarray(toe).ravel(), ref["toe"], atol=TOL)


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_swing_leg_segments_and_conventions(body):
    rng = np.random.default_rng(12)
    for q, hip in zip(np.column_stack([rng.uniform(-1.2, 1.2, 20), rng.uniform(0, 2, 20)]),
                      rng.uniform(-1, 1, (20, 2))):
        pts = swing_leg_points(body, q, hip)
        assert abs(np.linalg.norm(pts["knee"] - pts["hip"]) - body.l3) < TOL
        assert abs(np.linalg.norm(pts["ankle"] - pts["knee"]) - body.l4) < TOL
        _, ankle = swing_functions()["points"](q, hip, body.dynamic_parameters())
        np.testing.assert_allclose(pts["ankle"], np.asarray(ankle).ravel(), atol=TOL)
        # the foot hangs from the shank: ankle->knee is (sin, cos) of theta3 + theta4
        u = (pts["knee"] - pts["ankle"]) / body.l4
        np.testing.assert_allclose(u, [np.sin(q.sum()), np.cos(q.sum())], atol=TOL)
    # ERRATA conventions: theta3 < 0 puts the foot ahead of the hip, theta4 > 0 bends the knee back
    ahead = swing_leg_points(body, [-0.3, 0.0], [0.0, 1.0])
    assert ahead["ankle"][0] > 0 and ahead["toe"][0] > ahead["heel"][0]
    bent = swing_leg_points(body, [0.0, 0.5], [0.0, 1.0])
    assert bent["ankle"][0] < bent["knee"][0] == pytest.approx(0.0)


def test_stance_hip_and_upper_body():
    body = BODIES[0]
    w, t1, t2, wd, t1d = 0.9, 0.2, -0.1, 0.3, -1.0
    ankle = np.array([1.5, body.l9])
    pos, vel = stance_hip(body, [w, t1, t2, wd, t1d, 0.7], ankle)
    np.testing.assert_allclose(pos, ankle + w * np.array([np.sin(t1), np.cos(t1)]), atol=TOL)
    np.testing.assert_allclose(vel, [wd * np.sin(t1) + w * t1d * np.cos(t1),
                                     wd * np.cos(t1) - w * t1d * np.sin(t1)], atol=TOL)
    com = upper_body_com(body, [w, t1, t2], ankle)
    np.testing.assert_allclose(com, pos + body.r2 * np.array([np.sin(t2), np.cos(t2)]), atol=TOL)


def test_kinematics_reject_bad_shapes():
    with pytest.raises(ConfigError, match="ankle"):
        foot_points(BODIES[0], [0.0, 0.0, 0.0], 0.0, 1.5)
    with pytest.raises(ConfigError, match="q"):
        swing_leg_points(BODIES[0], [0.0], [0.0, 1.0])
