"""The body's few-call forms (issue #38, docs/performance.md "The body frames in fewer numpy calls")
give the numbers of the forms they replaced, to the bit: the forward
kinematics a joint at a time, the local rotations from 37 x 3 angles, the upper body's angles a
name at a time, the guard grids' padded rows."""
import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import pose, skeleton
from klaw_ocp.body_motion.swing_foot_guard import _Grids

BODY = Body(height=1.8, mass=80.0)
RNG = np.random.default_rng(38)


@pytest.mark.parametrize("n", [1, 7, 30])
def test_forward_kinematics_is_a_joint_at_a_time(n):
    root, angles = RNG.normal(size=(n, 3)), RNG.normal(size=(n, 56))
    signed = np.zeros((n, len(skeleton.JOINTS), 3))
    signed[:, skeleton._ANGLE_JOINT, skeleton._ANGLE_SLOT] = angles * skeleton._ANGLE_SIGN
    local = skeleton.zxy_matrices(signed[..., 0], signed[..., 1], signed[..., 2])
    assert np.array_equal(skeleton.local_rotations(angles), local)
    d = skeleton.Dimensions.of(BODY)
    offsets = np.array([j.offset(d) for j in skeleton.JOINTS], dtype=float)
    positions, rotations = np.empty((n, len(skeleton.JOINTS), 3)), np.empty_like(local)
    positions[:, 0], rotations[:, 0] = root, local[:, 0]
    for i in range(1, len(skeleton.JOINTS)):
        p = skeleton._PARENT_INDEX[i]
        positions[:, i] = positions[:, p] + rotations[:, p] @ offsets[i]
        rotations[:, i] = rotations[:, p] @ local[:, i]
    got = skeleton.forward_kinematics(BODY, root, angles)
    assert np.array_equal(got.positions, positions) and np.array_equal(got.rotations, rotations)
    for name, f in skeleton.END_SITES.items():
        k = skeleton.joint_index(name)
        assert np.array_equal(got.end_sites[name], positions[:, k] + rotations[:, k] @ np.asarray(f(d), float))
    for name, (joint, f) in skeleton.LANDMARKS.items():
        k = skeleton.joint_index(joint)
        assert np.array_equal(got.landmarks[name], positions[:, k] + rotations[:, k] @ np.asarray(f(d), float))


def test_upper_body_angles_are_the_weighted_totals():
    n = 9
    totals = {name: RNG.normal(size=n) for name in ("trunk_flexion", "trunk_bending", "trunk_rotation",
                                                    "head_flexion", "head_rotation")}
    arms = [{"right": RNG.normal(size=n), "left": 0.3} for _ in range(3)]
    angles = pose.upper_body_angles(pose.UpperBody(**totals, shoulder_flexion=arms[0], shoulder_abduction=arms[1],
                                                   elbow_flexion=arms[2]), n)
    for name, weight in pose.FLEXION_WEIGHTS.items():
        assert np.array_equal(angles[f"{name}_flexion"], weight * totals["trunk_flexion"])
    for name, weight in pose.ROTATION_WEIGHTS.items():
        if name != "C1":
            assert np.array_equal(angles[f"{name}_rotation"], weight * totals["trunk_rotation"])
    assert np.array_equal(angles["C1_rotation"], totals["head_rotation"])
    assert np.array_equal(angles["r_elbow_flexion"], arms[2]["right"]) and np.all(angles["l_elbow_flexion"] == 0.3)


def test_upper_body_checks_name_the_first_bad_value():
    good = pose.UpperBody.neutral()
    bad = pose.UpperBody(0.0, np.array([0.0, np.nan]), 0.0, 0.0, 0.0, *(dict(good.shoulder_flexion) for _ in range(3)))
    with pytest.raises(ValueError, match=r"upper_body\.trunk_bending: contains NaN"):
        pose.upper_body_angles(bad, 2)
    short = pose.UpperBody(0.0, 0.0, 0.0, 0.0, 0.0, {"right": np.zeros(3), "left": 0.0}, dict(good.shoulder_abduction),
                           dict(good.elbow_flexion))
    with pytest.raises(ValueError, match=r"upper_body\.shoulder_flexion\['right'\]: expected"):
        pose.upper_body_angles(short, 2)


def test_the_grids_padded_rows_hold_each_step_in_its_row():
    grids = _Grids([np.linspace(0.0, 0.1, 5), np.linspace(0.2, 0.5, 8)])
    values = RNG.normal(size=13)
    padded = grids.padded(values, -np.inf, band=2)
    assert padded.shape == (2, 12)
    assert np.array_equal(padded[0, 2:7], values[:5]) and np.array_equal(padded[1, 2:10], values[5:])
    assert np.all(padded[0, 7:] == -np.inf) and np.all(padded[:, :2] == -np.inf)
    backwards = grids.running_max(values, backwards=True)
    assert np.array_equal(backwards[:5], np.maximum.accumulate(values[:5][::-1])[::-1])
    assert np.array_equal(backwards[5:], np.maximum.accumulate(values[5:][::-1])[::-1])
