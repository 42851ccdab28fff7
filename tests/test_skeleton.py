"""The 37-joint, 56-angle skeleton (body_motion/skeleton.py) and its inverse (body_motion/pose.py)."""
from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import pose
from klaw_ocp.body_motion.skeleton import (ANGLE_NAMES, CERVICAL, END_SITES, JOINTS, LUMBAR, THORACIC,
                                           VERTEBRAE, angle_index, forward_kinematics, joint_index,
                                           local_rotations, rest_offsets, rest_root_position,
                                           segment_lengths, zxy_angles, zxy_matrices)

GEOMETRY_TOL = 1e-9   # m and rad: exact geometry, far above double round-off, far below any error
BODIES = [Body(1.8, 75.0), Body(1.2, 25.0)]
SIDES = (("r", "right"), ("l", "left"))


def standing(body: Body, angles: dict | None = None, n: int = 1):
    """FK of the rest pose with some angles set (name -> value), pelvis at standing height."""
    a = np.zeros((n, len(ANGLE_NAMES)))
    for name, value in (angles or {}).items():
        a[:, angle_index(name)] = value
    return forward_kinematics(body, np.tile(rest_root_position(body), (n, 1)), a)


def point(frames, name: str) -> np.ndarray:
    """A joint, end site or landmark of frame 0, shape (3,)."""
    if name in frames.landmarks:
        return frames.landmarks[name][0]
    if name.endswith("_end"):
        return frames.end_sites[name[:-4]][0]
    return frames.position(name)[0]


def leg_points(frames) -> dict:
    return {side: pose.LegPoints(hip=frames.position(f"{s}_hip"), knee=frames.position(f"{s}_knee"),
                                 ankle=frames.position(f"{s}_ankle"), heel=frames.landmarks[f"{s}_heel"],
                                 metatarsal=frames.position(f"{s}_toes"), toe=frames.end_sites[f"{s}_toes"])
            for s, side in SIDES}


# --- structure ------------------------------------------------------------------------------

def test_counts_match_the_paper():
    """37 joints, 24 of them vertebrae, 56 distinct angles, grouped as the brief counts them."""
    assert len(JOINTS) == 37
    assert len(VERTEBRAE) == 24 and (len(LUMBAR), len(THORACIC), len(CERVICAL)) == (5, 12, 7)
    assert {j.name for j in JOINTS} >= set(VERTEBRAE)
    assert len(ANGLE_NAMES) == 56 and len(set(ANGLE_NAMES)) == 56
    per_joint = {j.name: len(j.angle_names) for j in JOINTS}
    assert per_joint["pelvis"] == 3 and per_joint["C1"] == 2
    assert sum(per_joint[v] for v in LUMBAR) == 15 and sum(per_joint[v] for v in THORACIC) == 12
    assert sum(per_joint[v] for v in CERVICAL[:-1]) == 6
    for s, _ in SIDES:
        assert [per_joint[f"{s}_{j}"] for j in ("hip", "knee", "ankle", "toes", "shoulder", "elbow")] \
            == [3, 1, 1, 1, 2, 1]


def test_joint_tree_is_ordered_and_consistent():
    """Parents precede children, one root, every joint's angles, axes and signs line up in Z, X, Y
    order, end sites sit on leaves, and joint_index finds each joint."""
    seen = set()
    for i, joint in enumerate(JOINTS):
        assert (joint.parent is None) == (i == 0)
        assert joint.parent is None or joint.parent in seen
        seen.add(joint.name)
        assert len(joint.angle_names) == len(joint.axes) == len(joint.signs) >= 1
        order = [("z", "x", "y").index(ax) for ax in joint.axes]
        assert order == sorted(order) and all(sg in (1, -1) for sg in joint.signs)
        assert joint_index(joint.name) == i
    parents = {j.parent for j in JOINTS}
    assert all(leaf not in parents for leaf in END_SITES)
    with pytest.raises(ValueError, match="name"):
        joint_index("r_wrist")


def test_segment_lengths_are_the_body_dimensions():
    body = BODIES[0]
    lengths = segment_lengths(body)
    for s, _ in SIDES:
        assert abs(lengths[f"{s}_hip"] - body.l0 / 2) < GEOMETRY_TOL
        assert abs(lengths[f"{s}_knee"] - body.l3) < GEOMETRY_TOL
        assert abs(lengths[f"{s}_ankle"] - body.l4) < GEOMETRY_TOL
        assert abs(lengths[f"{s}_toes"] - body.l12) < GEOMETRY_TOL
        assert abs(lengths[f"{s}_toes_end"] - body.l13) < GEOMETRY_TOL
        assert abs(lengths[f"{s}_elbow"] - 0.186 * body.height) < GEOMETRY_TOL


# --- rest pose ------------------------------------------------------------------------------

@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_rest_pose_stands_upright_on_flat_feet(body):
    frames = standing(body)
    h, hip_height = body.height, body.l3 + body.l4 + body.l9
    np.testing.assert_allclose(frames.rotations[0], np.broadcast_to(np.eye(3), (37, 3, 3)),
                               atol=GEOMETRY_TOL)
    assert abs(point(frames, "C1_end")[1] - h) < GEOMETRY_TOL
    forward = math.sqrt(body.l12 ** 2 - body.l9 ** 2)
    for s, _ in SIDES:
        assert abs(point(frames, f"{s}_hip")[1] - hip_height) < GEOMETRY_TOL
        np.testing.assert_allclose(point(frames, f"{s}_heel")[:2], [-body.l8, 0.0], atol=GEOMETRY_TOL)
        np.testing.assert_allclose(point(frames, f"{s}_toes")[:2], [forward, 0.0], atol=GEOMETRY_TOL)
        np.testing.assert_allclose(point(frames, f"{s}_toes_end")[:2], [forward + body.l13, 0.0],
                                   atol=GEOMETRY_TOL)
        assert abs(point(frames, f"{s}_ankle")[1] - body.l9) < GEOMETRY_TOL
        # arms hang straight down from the shoulders
        shoulder, fingertip = point(frames, f"{s}_shoulder"), point(frames, f"{s}_elbow_end")
        np.testing.assert_allclose(fingertip[[0, 2]], shoulder[[0, 2]], atol=GEOMETRY_TOL)
        assert fingertip[1] < shoulder[1] - 0.5 * body.height * (0.186 + 0.146)
    hips = point(frames, "r_hip") - point(frames, "l_hip")
    np.testing.assert_allclose(hips, [0.0, 0.0, body.l0], atol=GEOMETRY_TOL)
    np.testing.assert_allclose(point(frames, "pelvis"), [0.0, hip_height, 0.0], atol=GEOMETRY_TOL)
    assert set(rest_offsets(body)) == {j.name for j in JOINTS}


# --- signs ----------------------------------------------------------------------------------

SIGN_CASES = [  # angle, point that moves, world axis (0 x, 1 y, 2 z), expected direction
    ("r_hip_flexion", "r_knee", 0, +1), ("l_hip_flexion", "l_knee", 0, +1),
    ("r_hip_adduction", "r_knee", 2, -1), ("l_hip_adduction", "l_knee", 2, +1),
    ("r_hip_rotation", "r_toes_end", 2, -1), ("l_hip_rotation", "l_toes_end", 2, +1),
    ("r_knee_flexion", "r_ankle", 0, -1), ("l_knee_flexion", "l_ankle", 0, -1),
    ("r_ankle_dorsiflexion", "r_toes_end", 1, +1), ("r_ankle_dorsiflexion", "r_heel", 1, -1),
    ("r_toe_dorsiflexion", "r_toes_end", 1, +1), ("l_toe_dorsiflexion", "l_toes_end", 1, +1),
    ("pelvis_tilt", "L5", 0, +1), ("pelvis_list", "r_hip", 1, +1), ("pelvis_list", "l_hip", 1, -1),
    ("pelvis_rotation", "r_hip", 0, +1), ("pelvis_rotation", "l_hip", 0, -1),
    ("L5_flexion", "C1_end", 0, +1), ("L3_bending", "C1_end", 2, +1),
    ("T8_rotation", "r_shoulder", 0, +1), ("L1_rotation", "l_shoulder", 0, -1),
    ("C1_flexion", "C1_end", 0, +1),
    ("r_shoulder_flexion", "r_elbow", 0, +1), ("l_shoulder_flexion", "l_elbow", 0, +1),
    ("r_shoulder_abduction", "r_elbow", 2, +1), ("l_shoulder_abduction", "l_elbow", 2, -1),
    ("r_elbow_flexion", "r_elbow_end", 0, +1), ("l_elbow_flexion", "l_wrist", 0, +1),
]


@pytest.mark.parametrize("angle,moved,axis,direction", SIGN_CASES,
                         ids=[f"{c[0]}->{c[1]}" for c in SIGN_CASES])
def test_positive_angles_move_the_body_the_clinical_way(angle, moved, axis, direction):
    body = BODIES[0]
    shift = point(standing(body, {angle: 0.3}), moved) - point(standing(body), moved)
    assert direction * shift[axis] > 1e-3   # m; every case moves its point by centimetres


def test_head_rotation_turns_the_face_to_the_left():
    """C1_rotation + turns the head's forward axis towards -z, the same sense as trunk rotation."""
    gaze = standing(BODIES[0], {"C1_rotation": 0.4}).rotation("C1")[0] @ [1.0, 0.0, 0.0]
    np.testing.assert_allclose(gaze, [math.cos(0.4), 0.0, -math.sin(0.4)], atol=GEOMETRY_TOL)


def test_toe_dorsiflexion_keeps_the_metatarsal_head():
    body = BODIES[0]
    moved = point(standing(body, {"r_toe_dorsiflexion": 0.5}), "r_toes_end")
    head = point(standing(body), "r_toes")
    np.testing.assert_allclose(moved - head, body.l13 * np.array([math.cos(0.5), math.sin(0.5), 0.0]),
                               atol=GEOMETRY_TOL)


# --- rotation convention --------------------------------------------------------------------

def test_zxy_matrices_compose_elementary_rotations_and_invert():
    rng = np.random.default_rng(3)
    z, x, y = rng.uniform(-3, 3, 50), rng.uniform(-1.5, 1.5, 50), rng.uniform(-3, 3, 50)

    def elementary(axis, t):
        c, s = math.cos(t), math.sin(t)
        return {"z": np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]),
                "x": np.array([[1, 0, 0], [0, c, -s], [0, s, c]]),
                "y": np.array([[c, 0, s], [0, 1, 0], [-s, 0, c]])}[axis]
    matrices = zxy_matrices(z, x, y)
    for k in range(50):
        expected = elementary("z", z[k]) @ elementary("x", x[k]) @ elementary("y", y[k])
        np.testing.assert_allclose(matrices[k], expected, atol=GEOMETRY_TOL)
    for got, want in zip(zxy_angles(matrices), (z, x, y)):
        np.testing.assert_allclose(got, want, atol=GEOMETRY_TOL)


def test_local_rotations_checks_its_argument():
    assert local_rotations(np.zeros((4, 56))).shape == (4, 37, 3, 3)
    with pytest.raises(ValueError, match="angles"):
        local_rotations(np.zeros((4, 55)))
    with pytest.raises(ValueError, match="root_position"):
        forward_kinematics(BODIES[0], np.zeros((3, 3)), np.zeros((4, 56)))


# --- inverse: angles from world geometry ----------------------------------------------------

def random_upper_body(rng, n) -> pose.UpperBody:
    def arms(lo, hi):
        return {"right": rng.uniform(lo, hi, n), "left": rng.uniform(lo, hi, n)}
    return pose.UpperBody(trunk_flexion=rng.uniform(-0.1, 0.3, n), trunk_bending=rng.uniform(-0.1, 0.1, n),
                          trunk_rotation=rng.uniform(-0.2, 0.2, n), head_flexion=rng.uniform(-0.2, 0.2, n),
                          head_rotation=rng.uniform(-0.3, 0.3, n), shoulder_flexion=arms(-0.5, 0.5),
                          shoulder_abduction=arms(0.0, 0.2), elbow_flexion=arms(0.0, 1.0))


def random_pose(rng, n: int):
    """Plausible walking angles (rad) for pelvis and legs, the upper body from random totals."""
    upper = random_upper_body(rng, n)
    angles = np.zeros((n, 56))
    ranges = {"pelvis_tilt": (-0.2, 0.2), "pelvis_list": (-0.15, 0.15), "pelvis_rotation": (-0.3, 0.3),
              "hip_flexion": (-0.5, 0.8), "hip_adduction": (-0.25, 0.25), "hip_rotation": (-0.35, 0.35),
              "knee_flexion": (0.0, 1.3), "ankle_dorsiflexion": (-0.5, 0.35), "toe_dorsiflexion": (-0.1, 0.7)}
    for name, (lo, hi) in ranges.items():
        for column in [name] if name.startswith("pelvis") else [f"{s}_{name}" for s, _ in SIDES]:
            angles[:, angle_index(column)] = rng.uniform(lo, hi, n)
    # straight and nearly straight knees: thigh and shank parallel, the hinge comes from the foot
    angles[:4, angle_index("r_knee_flexion")] = [0.0, 1e-9, 1e-6, -1e-4]
    angles[4:8, angle_index("l_knee_flexion")] = [0.0, 1e-9, 1e-6, -1e-4]
    for name, values in pose.upper_body_angles(upper, n).items():
        angles[:, angle_index(name)] = values
    root = np.column_stack([rng.uniform(-5, 5, n), rng.uniform(0.8, 1.0, n), rng.uniform(-0.1, 0.1, n)])
    return root, angles, upper


@pytest.mark.parametrize("body", BODIES, ids=["1.8m", "1.2m"])
def test_round_trip_recovers_every_angle_and_position(body):
    rng = np.random.default_rng(20240611)
    root, angles, upper = random_pose(rng, 300)
    frames = forward_kinematics(body, root, angles)
    pelvis_angles = angles[:, [angle_index(a) for a in ("pelvis_tilt", "pelvis_list", "pelvis_rotation")]]
    recovered = pose.skeleton_angles(body, root, pelvis_angles, leg_points(frames), upper)
    assert recovered.shape == (300, 56)
    worst = np.abs(recovered - angles).max(axis=0)
    assert worst.max() < GEOMETRY_TOL, ANGLE_NAMES[int(np.argmax(worst))]
    again = forward_kinematics(body, root, recovered)
    np.testing.assert_allclose(again.positions, frames.positions, rtol=0, atol=GEOMETRY_TOL)
    for name in END_SITES:
        np.testing.assert_allclose(again.end_sites[name], frames.end_sites[name], rtol=0, atol=GEOMETRY_TOL)


def test_leg_angles_from_hand_built_sagittal_geometry():
    """Points built with plain trigonometry (not the FK): thigh a forward of the vertical, knee
    flexion k, rear foot pitched p toes-up, toe segment pitched q: hip flexion a, knee flexion k,
    ankle dorsiflexion p - (a - k), toe dorsiflexion q - p."""
    body = BODIES[0]
    a, k, p, q = 0.35, 0.6, -0.2, 0.25
    forward = math.sqrt(body.l12 ** 2 - body.l9 ** 2)

    def rotate(v, t):
        return np.array([math.cos(t) * v[0] - math.sin(t) * v[1], math.sin(t) * v[0] + math.cos(t) * v[1], 0.0])
    centre = np.array([[0.2, 0.9, 0.0]])
    legs = {}
    for s, side in SIDES:
        hip = centre[0] + [0.0, 0.0, (1 if s == "r" else -1) * body.l0 / 2]
        knee = hip + body.l3 * np.array([math.sin(a), -math.cos(a), 0.0])
        ankle = knee + body.l4 * np.array([math.sin(a - k), -math.cos(a - k), 0.0])
        metatarsal = ankle + rotate((forward, -body.l9), p)
        legs[side] = pose.LegPoints(*(v[None] for v in (
            hip, knee, ankle, ankle + rotate((-body.l8, -body.l9), p), metatarsal,
            metatarsal + body.l13 * np.array([math.cos(q), math.sin(q), 0.0]))))
    got = pose.skeleton_angles(body, centre, np.zeros((1, 3)), legs, pose.UpperBody.neutral())[0]
    for s, _ in SIDES:
        expected = {"hip_flexion": a, "hip_adduction": 0.0, "hip_rotation": 0.0, "knee_flexion": k,
                    "ankle_dorsiflexion": p - (a - k), "toe_dorsiflexion": q - p}
        for name, value in expected.items():
            assert abs(got[angle_index(f"{s}_{name}")] - value) < GEOMETRY_TOL, (s, name)


def test_a_hip_away_from_the_pelvis_is_refused_naming_the_side():
    body = BODIES[0]
    root, angles, upper = random_pose(np.random.default_rng(5), 10)
    frames = forward_kinematics(body, root, angles)
    legs = leg_points(frames)
    moved = legs["left"].hip.copy()
    moved[3, 0] += 1e-4
    legs["left"] = pose.LegPoints(moved, legs["left"].knee, legs["left"].ankle, legs["left"].heel,
                                  legs["left"].metatarsal, legs["left"].toe)
    with pytest.raises(ValueError, match=r"legs\['left'\]\.hip.*frame 3"):
        pose.skeleton_angles(body, root, angles[:, :3], legs, upper)
    with pytest.raises(ValueError, match="pelvis_angles"):
        pose.skeleton_angles(body, root, angles[:5, :3], leg_points(frames), upper)


# --- upper body -----------------------------------------------------------------------------

def test_trunk_totals_are_spread_over_the_spine_exactly():
    rng = np.random.default_rng(8)
    upper = random_upper_body(rng, 40)
    angles = pose.upper_body_angles(upper, 40)
    for weights in (pose.FLEXION_WEIGHTS, pose.BENDING_WEIGHTS, pose.ROTATION_WEIGHTS):
        assert abs(sum(weights.values()) - 1.0) < 1e-15 and min(weights.values()) >= 0.0
    thoracic_share = sum(pose.ROTATION_WEIGHTS[v] for v in THORACIC)
    assert thoracic_share > 0.75   # the shoulders' counter-rotation is mostly thoracic
    np.testing.assert_allclose(sum(angles[f"{v}_flexion"] for v in LUMBAR), upper.trunk_flexion, atol=1e-15)
    np.testing.assert_allclose(sum(angles[f"{v}_bending"] for v in LUMBAR), upper.trunk_bending, atol=1e-15)
    np.testing.assert_allclose(sum(angles[f"{v}_rotation"] for v in VERTEBRAE[:-1]), upper.trunk_rotation,
                               atol=1e-15)
    np.testing.assert_allclose(angles["C1_flexion"], upper.head_flexion)
    np.testing.assert_allclose(angles["C1_rotation"], upper.head_rotation)
    np.testing.assert_allclose(angles["l_elbow_flexion"], upper.elbow_flexion["left"])
    np.testing.assert_allclose(angles["r_shoulder_abduction"], upper.shoulder_abduction["right"])


@pytest.mark.parametrize("total,axis", [("trunk_flexion", "flexion"), ("trunk_bending", "bending"),
                                        ("trunk_rotation", "rotation")])
def test_a_single_trunk_total_turns_the_top_of_the_spine_by_that_angle(total, axis):
    """With only one total non-zero the vertebral rotations share one axis, so the head joint's
    frame (C1, head angles zero) is turned by exactly the total relative to the pelvis."""
    value = 0.3
    upper = dataclasses.replace(pose.UpperBody.neutral(), **{total: value})
    angles = np.zeros((1, 56))
    for name, values in pose.upper_body_angles(upper, 1).items():
        angles[:, angle_index(name)] = values
    top = forward_kinematics(BODIES[0], np.zeros((1, 3)), angles).rotation("C1")[0]
    expected = {"flexion": zxy_matrices(-value, 0.0, 0.0), "bending": zxy_matrices(0.0, value, 0.0),
                "rotation": zxy_matrices(0.0, 0.0, value)}[axis]
    np.testing.assert_allclose(top, expected, atol=GEOMETRY_TOL)


def test_upper_body_arguments_are_checked():
    bad = dataclasses.replace(pose.UpperBody.neutral(), elbow_flexion={"right": 0.0})
    with pytest.raises(ValueError, match="elbow_flexion"):
        pose.upper_body_angles(bad, 3)
    short = dataclasses.replace(pose.UpperBody.neutral(), trunk_flexion=np.zeros(2))
    with pytest.raises(ValueError, match="trunk_flexion"):
        pose.upper_body_angles(short, 3)
