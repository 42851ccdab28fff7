"""The legs' angles of the skeleton from their world points, compiled (:mod:`klaw_ocp.kernels`).

:func:`.pose.skeleton_angles` turns each leg's six world points into its segments' frames (the
thigh, shank, foot and toe, on the hinge axis that the foot and the hip-ankle line span) and
those into the hip's three angles against the pelvis and the knee's, ankle's and toes' hinge
angles. As numpy over a step's 15-60 frames that was about 200 small array operations, their
fixed cost the whole time (0.25 ms a step on the reference machine, on the playground's path
from asking for a step to its message: docs/serve.md); as one CasADi Function of a frame, mapped
over BLOCK frames and compiled as the solvers' kernels are, it is one call a block.

A frame's function, in the column order :data:`LEG_COLUMNS` names:

- ``angles`` (12): for the right leg then the left, the hip's flexion, adduction and rotation
  (the zxy angles of the thigh's frame in the pelvis's, each times its joint's sign), then the
  knee, ankle and toes (each hinge's angle about the common z axis, times its sign);
- ``miss`` (2): each hip point's distance from where the pelvis puts that hip;
- ``norms`` (18): for each leg, the lengths each unit vector was divided by, in the order the
  checks name them (:data:`NORM_CHECKS`): the hinge axis, the four bones, the two leg frames'
  x axes, the two foot frames' y axes. One below 1e-12 is a degenerate leg, which the caller
  refuses naming it, as the numpy form did.

The arithmetic is numpy's in its order (cross products, sums of squares, matrix products), so
the angles agree with it to a few units in the last place (tests/test_skeleton.py).
"""
from __future__ import annotations

import sys
from functools import lru_cache

import casadi as ca
import numpy as np

from ..casadi_builds import built_once
from ..kernels import KernelLibrary, source_key
from .kernel_forms import evaluate, mapped_library
from . import skeleton
from .skeleton import ANGLE_NAMES, JOINTS, SIDES

#: frames per kernel call: a step's frames at 30 fps fit one call from 1 km/h up; longer inputs
#: (a whole walk's body) take one call per BLOCK frames, the last block padded
BLOCK = 32
POINTS = ("hip", "knee", "ankle", "heel", "metatarsal", "toe")
_JOINT = {j.name: j for j in JOINTS}
#: the angles' columns in ANGLE_NAMES, in the kernel's output order
LEG_COLUMNS = np.array([ANGLE_NAMES.index(name) for s, _ in SIDES
                        for joint in ("hip", "knee", "ankle", "toes") for name in _JOINT[f"{s}_{joint}"].angle_names])
_SIGNS = [sign for s, _ in SIDES for joint in ("hip", "knee", "ankle", "toes") for sign in _JOINT[f"{s}_{joint}"].signs]
#: what each of a leg's nine norms is called where it vanishes (the checks in this order; the
#: first failing one is named), and how many of the nine each covers
NORM_CHECKS = (("legs: the leg plane (foot axis parallel to ankle-hip)", 1), ("legs: hip-knee", 1),
               ("legs: knee-ankle", 1), ("legs: heel-metatarsal", 1), ("legs: metatarsal-toe", 1),
               ("leg frame", 2), ("foot frame", 2))
OUTPUTS = {"angles": 12, "miss": 2, "norms": 18}


def _cross(a, b):
    return ca.vertcat(a[1] * b[2] - a[2] * b[1], a[2] * b[0] - a[0] * b[2], a[0] * b[1] - a[1] * b[0])


def _length(v):
    return ca.sqrt(v[0] * v[0] + v[1] * v[1] + v[2] * v[2])


def _frames(p: dict, norms: list) -> tuple:
    """The thigh's, shank's, foot's and toe's world frames (3 x 3, columns x, y, z) of one leg's
    points ``p``; each unit vector's length appended to ``norms``."""
    def unit(v):
        length = _length(v)
        norms.append(length)
        return v / length
    hinge = unit(_cross(p["metatarsal"] - p["heel"], p["hip"] - p["ankle"]))
    bones = [unit(p[end] - p[start]) for start, end in
             (("knee", "hip"), ("ankle", "knee"), ("heel", "metatarsal"), ("metatarsal", "toe"))]
    legs = []
    for up in bones[:2]:                                  # the thigh's and shank's y run up the bones
        x = unit(_cross(up, hinge))
        legs.append(ca.horzcat(x, up, _cross(x, up)))
    feet = []
    for forward in bones[2:]:                             # the foot's and toe's x run forward
        y = unit(_cross(hinge, forward))
        feet.append(ca.horzcat(forward, y, _cross(forward, y)))
    return (*legs, *feet)


def _hinge(parent, child):
    """The angle about the shared z axis of ``parent^T child``."""
    local = ca.mtimes(parent.T, child)
    return ca.atan2(local[1, 0], local[0, 0])


def frame_function() -> ca.Function:
    """One frame: (its inputs (48: the pelvis rotation row by row (9), the pelvis centre (3), both
    legs' points (36: right then left, POINTS order, x y z)), the hips' offsets from the pelvis
    centre in its frame (6: right, left)) -> (angles (12), miss (2), norms (18))."""
    frame, offsets = ca.SX.sym("frame", 48), ca.SX.sym("offsets", 6)
    pelvis = ca.vertcat(*[ca.horzcat(*[frame[3 * i + j] for j in range(3)]) for i in range(3)])
    centre, points = frame[9:12], frame[12:]
    angles, miss, norms = [], [], []
    for side in range(2):
        p = {name: points[18 * side + 3 * k:18 * side + 3 * k + 3] for k, name in enumerate(POINTS)}
        hip = centre + ca.mtimes(pelvis, offsets[3 * side:3 * side + 3])
        miss.append(_length(p["hip"] - hip))
        thigh, shank, foot, toe = _frames(p, norms)
        r = ca.mtimes(pelvis.T, thigh)                     # the thigh in the pelvis's frame: zxy angles
        x = ca.atan2(r[2, 1], ca.hypot(r[2, 0], r[2, 2]))
        y = ca.atan2(-r[2, 0], r[2, 2])
        z = ca.atan2(-r[0, 1], r[1, 1])
        angles += [z, x, y, _hinge(thigh, shank), _hinge(shank, foot), _hinge(foot, toe)]
    signed = [sign * a for sign, a in zip(_SIGNS, angles)]
    return ca.Function("body_leg_angles", [frame, offsets], [ca.vertcat(*signed), ca.vertcat(*miss), ca.vertcat(*norms)],
                       ["frame", "offsets"], list(OUTPUTS))


@built_once
def library() -> KernelLibrary:
    """The kernel's library (built once; :meth:`~klaw_ocp.kernels.KernelLibrary.load` compiles it)."""
    # the key: the source of the modules whose code builds the expressions (the joints' signs)
    return mapped_library([source_key(sys.modules[__name__], skeleton)], frame_function, {"body_leg_angles_block": BLOCK})


@lru_cache(maxsize=None)
def _kernel():
    return library().functions()["body_leg_angles_block"]


def leg_angles(rotation: np.ndarray, centre: np.ndarray, points: np.ndarray, offsets: np.ndarray) -> dict:
    """The kernel over n frames: pelvis rotations (n, 3, 3), centres (n, 3), both legs' points
    (2 (right, left), 6 (POINTS), n, 3), the hips' offsets (6,) -> OUTPUTS name -> (n, size)."""
    n = len(centre)
    frames = np.empty((n, 48))
    frames[:, :9] = rotation.reshape(n, 9)
    frames[:, 9:12] = centre
    frames[:, 12:].reshape(n, 2, 6, 3)[...] = points.transpose(2, 0, 1, 3)
    return evaluate(_kernel(), BLOCK, frames, offsets, OUTPUTS)
