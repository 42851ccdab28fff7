"""The legs' angles compiled (body_motion/leg_angles.py, issue #38): the numbers of a plain numpy
form of the same geometry (np.cross, np.linalg.norm, the zxy angles of the thigh in the pelvis) to
round-off, whatever the number of frames against the kernel's block; CasADi's own evaluation (no
compiler) the same; degenerate legs and misplaced hips refused naming what and the frame."""
import numpy as np
import pytest

from klaw_ocp.body import Body
from klaw_ocp.body_motion import leg_angles, pose
from klaw_ocp.body_motion.kernel_forms import mapped_library
from klaw_ocp.body_motion.skeleton import ANGLE_NAMES, SIDES, forward_kinematics, zxy_angles
from test_skeleton import leg_points, random_pose

BODY = Body(height=1.8, mass=80.0)


def numpy_leg_angles(points: pose.LegPoints, pelvis: np.ndarray) -> dict:
    """The hip's zxy angles and the three hinge angles of one leg, with numpy's own functions."""
    def unit(v):
        return v / np.linalg.norm(v, axis=-1, keepdims=True)
    hinge = unit(np.cross(points.metatarsal - points.heel, points.hip - points.ankle))
    frames = {}
    for name, (start, end) in {"thigh": ("knee", "hip"), "shank": ("ankle", "knee")}.items():
        up = unit(getattr(points, end) - getattr(points, start))
        x = unit(np.cross(up, hinge))
        frames[name] = np.stack([x, up, np.cross(x, up)], axis=-1)
    for name, (start, end) in {"foot": ("heel", "metatarsal"), "toe": ("metatarsal", "toe")}.items():
        forward = unit(getattr(points, end) - getattr(points, start))
        y = unit(np.cross(hinge, forward))
        frames[name] = np.stack([forward, y, np.cross(forward, y)], axis=-1)

    def hinge_angle(parent, child):
        local = np.einsum("nji,njk->nik", parent, child)
        return np.arctan2(local[:, 1, 0], local[:, 0, 0])
    z, x, y = zxy_angles(np.einsum("nji,njk->nik", pelvis, frames["thigh"]))
    return {"hip": (z, x, y), "knee": hinge_angle(frames["thigh"], frames["shank"]),
            "ankle": hinge_angle(frames["shank"], frames["foot"]), "toes": hinge_angle(frames["foot"], frames["toe"])}


def _pose(n: int, seed: int = 38):
    root, angles, upper = random_pose(np.random.default_rng(seed), max(n, 8))     # (its straight knees: 8 frames)
    root, angles = root[:n], angles[:n]
    upper = pose.UpperBody(*[v[:n] if isinstance(v, np.ndarray) else
                             {k: a[:n] for k, a in v.items()} if isinstance(v, dict) else v
                             for v in (getattr(upper, f) for f in pose.UpperBody.__dataclass_fields__)])
    frames = forward_kinematics(BODY, root, angles)
    return root, angles, upper, leg_points(frames)


@pytest.mark.parametrize("n", [1, 17, leg_angles.BLOCK, leg_angles.BLOCK + 1, 3 * leg_angles.BLOCK + 5])
def test_compiled_angles_are_numpys_geometry(n):
    root, angles, upper, legs = _pose(n)
    got = pose.skeleton_angles(BODY, root, angles[:, :3], legs, upper)
    rotation = pose.pelvis_rotations(angles[:, :3])
    joints = {j.name: j for j in pose.JOINTS}
    for s, side in SIDES:
        want = numpy_leg_angles(legs[side], rotation)
        hip = joints[f"{s}_hip"]
        for name, sign, value in zip(hip.angle_names, hip.signs, want["hip"]):
            assert np.abs(got[:, ANGLE_NAMES.index(name)] - sign * value).max() < 1e-13, name
        for joint in ("knee", "ankle", "toes"):
            hinge = joints[f"{s}_{joint}"]
            column = ANGLE_NAMES.index(hinge.angle_names[0])
            assert np.abs(got[:, column] - hinge.signs[0] * want[joint]).max() < 1e-13, joint
    # and the angles the legs were built from (the round trip of tests/test_skeleton.py)
    assert np.abs(got - angles).max() < 1e-9


def test_casadi_evaluation_gives_the_compiled_numbers(monkeypatch):
    root, angles, _, legs = _pose(40)
    compiled = pose.skeleton_angles(BODY, root, angles[:, :3], legs, None)
    library = mapped_library(["test"], leg_angles.frame_function, {"body_leg_angles_block": leg_angles.BLOCK})
    monkeypatch.setattr(leg_angles, "_kernel", lambda: library.functions()["body_leg_angles_block"])
    monkeypatch.setenv("KLAW_OCP_JIT", "0")
    by_casadi = pose.skeleton_angles(BODY, root, angles[:, :3], legs, None)
    assert type(leg_angles._kernel()).__name__ == "CasadiFunction"
    assert np.abs(by_casadi - compiled).max() < 1e-14


def test_no_frames_no_angles():
    empty = pose.LegPoints(*[np.zeros((0, 3))] * 6)
    assert pose.skeleton_angles(BODY, np.zeros((0, 3)), np.zeros((0, 3)), {"right": empty, "left": empty},
                                None).shape == (0, 56)


@pytest.mark.parametrize("change, message", [
    (lambda p: {"knee": p.hip.copy()}, "legs: hip-knee: zero length in frame 3"),
    (lambda p: {"toe": p.metatarsal.copy()}, "legs: metatarsal-toe: zero length in frame 3"),
    # the foot's axis along the hip-ankle line: no leg plane
    (lambda p: {"metatarsal": p.heel + (p.hip - p.ankle)}, "legs: the leg plane (foot axis parallel to ankle-hip): "
                                                            "zero length in frame 3"),
    (lambda p: {"hip": p.hip + [0.0, 0.0, 1e-3]}, "legs['left'].hip: 0.001 m from the pelvis's left hip in frame 3"),
])
def test_degenerate_legs_are_refused_naming_the_frame(change, message):
    root, angles, _, legs = _pose(10)
    left = legs["left"]
    broken = {name: getattr(left, name).copy() for name in leg_angles.POINTS}
    for name, value in change(left).items():
        broken[name][3] = value[3]
    legs = dict(legs, left=pose.LegPoints(**broken))
    with pytest.raises(ValueError, match="^" + message.replace("(", r"\(").replace(")", r"\)").replace("[", r"\[")
                       .replace(".", r"\.")):
        pose.skeleton_angles(BODY, root, angles[:, :3], legs, None)
