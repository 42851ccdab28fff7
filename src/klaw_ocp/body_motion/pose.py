"""The skeleton's 56 angles from world geometry: the inverse of :mod:`.skeleton` (docs/skeleton.md).

The legs come as world points (hip, knee, ankle, heel, first metatarsal head, toe tip) from the
virtual leg and the swing dynamics; the pelvis as its centre and three angles (the determinants of
gait); the spine, head and arms as a few totals (:class:`UpperBody`) that this module spreads over
the 24 vertebrae.

Every array is over n frames; all angles are in radians with the signs of :mod:`.skeleton`.
"""
from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from ..body import Body
from .skeleton import (ANGLE_NAMES, JOINTS, LUMBAR, SIDES, VERTEBRAE, Dimensions, frames_array,
                       zxy_angles, zxy_matrices)

#: Hip points further than this (m) from the pelvis's own hips mean the caller's pelvis and legs
#: disagree: the angles would silently describe another pose.
HIP_TOLERANCE_M = 1e-6

# How the trunk totals are spread over the vertebrae. Our choice, in proportion to the
# representative segmental ranges of motion of White & Panjabi, "Clinical Biomechanics of the
# Spine" (2nd ed., 1990), as we recall them, in degrees; keyed by the joint named after the
# vertebra above each motion segment (L5 = L5/S1).
#   flexion/extension, lumbar: L1/L2 12, L2/L3 14, L3/L4 15, L4/L5 16, L5/S1 17;
#   lateral bending (one side), lumbar: 6, 6, 8, 6, 3 (L1/L2 .. L5/S1);
#   axial rotation (one side): lumbar 2, 2, 2, 2, 1; thoracic T12/L1 .. T1/T2: 2, 2, 2, 4, 6, 8,
#   8, 8, 8, 8, 8, 9. The cervical joints C7..C2 get a token 1 each (our choice): the neck's large
#   rotation belongs to the head's turn (C1, driven by head_rotation), and the counter-rotation of
#   the shoulders against the pelvis in walking happens in the thoracic spine.
_FLEXION_DEGREES = {"L5": 17, "L4": 16, "L3": 15, "L2": 14, "L1": 12}
_BENDING_DEGREES = {"L5": 3, "L4": 6, "L3": 8, "L2": 6, "L1": 6}
_ROTATION_DEGREES = {"L5": 1, "L4": 2, "L3": 2, "L2": 2, "L1": 2,
                     "T12": 2, "T11": 2, "T10": 2, "T9": 4, "T8": 6, "T7": 8, "T6": 8, "T5": 8,
                     "T4": 8, "T3": 8, "T2": 8, "T1": 9,
                     "C7": 1, "C6": 1, "C5": 1, "C4": 1, "C3": 1, "C2": 1, "C1": 0}


def _normalised(degrees: dict) -> dict:
    total = sum(degrees.values())
    return {name: value / total for name, value in degrees.items()}


#: Vertebra -> share of trunk_flexion (lumbar joints; sums to 1).
FLEXION_WEIGHTS = _normalised(_FLEXION_DEGREES)
#: Vertebra -> share of trunk_bending (lumbar joints; sums to 1).
BENDING_WEIGHTS = _normalised(_BENDING_DEGREES)
#: Vertebra -> share of trunk_rotation (L5..C2, mostly thoracic; C1 is the head's; sums to 1).
ROTATION_WEIGHTS = _normalised(_ROTATION_DEGREES)

_COLUMN = {name: i for i, name in enumerate(ANGLE_NAMES)}
_JOINT = {j.name: j for j in JOINTS}


@dataclass(frozen=True)
class LegPoints:
    """One leg's world points, each shape (n, 3) (m): hip joint centre, knee, ankle, heel, first
    metatarsal head and toe tip. They must lie in one plane (the leg plane), with |hip - knee| = l3,
    |knee - ankle| = l4 and the foot points rigid with the foot (:mod:`.skeleton`)."""
    hip: np.ndarray
    knee: np.ndarray
    ankle: np.ndarray
    heel: np.ndarray
    metatarsal: np.ndarray
    toe: np.ndarray


@dataclass(frozen=True)
class UpperBody:
    """Per-frame totals, each shape (n,) or a scalar (rad).

    ``trunk_flexion`` (+ forward lean), ``trunk_bending`` (+ to the right) and ``trunk_rotation``
    (+ front to the left) are relative to the pelvis; ``head_flexion`` (+ nod forward) and
    ``head_rotation`` (+ face to the left) relative to the top of the spine (C2).
    ``shoulder_flexion``, ``shoulder_abduction`` and ``elbow_flexion`` map "right" and "left" to
    the arm's angles.
    """
    trunk_flexion: np.ndarray
    trunk_bending: np.ndarray
    trunk_rotation: np.ndarray
    head_flexion: np.ndarray
    head_rotation: np.ndarray
    shoulder_flexion: dict
    shoulder_abduction: dict
    elbow_flexion: dict

    @classmethod
    def neutral(cls) -> "UpperBody":
        """Upright trunk, head level and forward, arms hanging."""
        arms = {"right": 0.0, "left": 0.0}
        return cls(0.0, 0.0, 0.0, 0.0, 0.0, dict(arms), dict(arms), dict(arms))


def _per_frame(value, name: str, n: int) -> np.ndarray:
    a = np.asarray(value, dtype=float)
    if a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
        raise ValueError(f"{name}: expected a scalar or shape ({n},), got {a.shape}")
    if not np.all(np.isfinite(a)):
        raise ValueError(f"{name}: contains NaN or infinite values")
    return np.full(n, a)   # a copy: the caller may write into the angles


def _unit(v: np.ndarray, name: str) -> np.ndarray:
    norm = np.linalg.norm(v, axis=-1, keepdims=True)
    if np.any(norm < 1e-12):
        raise ValueError(f"{name}: zero length in frame {int(np.argmin(norm[:, 0]))}")
    return v / norm


def _cross(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """np.cross of (n, 3) arrays, its products and differences in its order (the same bits):
    np.cross's axis handling cost 40 us a call, 18 calls in every evaluation of the body."""
    a0, a1, a2, b0, b1, b2 = a[:, 0], a[:, 1], a[:, 2], b[:, 0], b[:, 1], b[:, 2]
    return np.column_stack([a1 * b2 - a2 * b1, a2 * b0 - a0 * b2, a0 * b1 - a1 * b0])


def _frame_from_y(y_axis: np.ndarray, hinge: np.ndarray) -> np.ndarray:
    """Shape (n, 3, 3): axes as columns, y given, z the hinge made orthogonal to y."""
    x = _unit(_cross(y_axis, hinge), "leg frame")
    return np.stack([x, y_axis, _cross(x, y_axis)], axis=-1)


def _frame_from_x(x_axis: np.ndarray, hinge: np.ndarray) -> np.ndarray:
    """Shape (n, 3, 3): axes as columns, x given, z the hinge made orthogonal to x."""
    y = _unit(_cross(hinge, x_axis), "foot frame")
    return np.stack([x_axis, y, _cross(x_axis, y)], axis=-1)


def _hinge_angle(parent: np.ndarray, child: np.ndarray) -> np.ndarray:
    """Shape (n,): the angle about z of ``parent^T @ child`` (both share their z axis)."""
    local = np.swapaxes(parent, -1, -2) @ child
    return np.arctan2(local[:, 1, 0], local[:, 0, 0])


def pelvis_rotations(pelvis_angles: np.ndarray) -> np.ndarray:
    """Pelvis tilt, list, rotation shape (n, 3) (rad) -> its world rotation shape (n, 3, 3)."""
    a = frames_array(pelvis_angles, "pelvis_angles", 3)
    pelvis = JOINTS[0]
    return zxy_matrices(*(sign * a[:, k] for k, sign in enumerate(pelvis.signs)))


def hip_positions(body: Body, pelvis_center: np.ndarray, pelvis_angles: np.ndarray) -> dict:
    """"right"/"left" -> the hip joint centres shape (n, 3) that the pelvis pose places (m)."""
    centre = frames_array(pelvis_center, "pelvis_center", 3)
    rotation = pelvis_rotations(pelvis_angles)
    d = Dimensions.of(body)
    return {side: centre + rotation @ np.asarray(_JOINT[f"{s}_hip"].offset(d), dtype=float)
            for s, side in SIDES}


def leg_segment_rotations(points: LegPoints) -> dict:
    """World rotations shape (n, 3, 3) of "thigh", "shank", "foot" and "toe" (the frames of the
    hip, knee, ankle and toes joints) from one leg's points.

    The common z axis is the hinge ``unit((metatarsal - heel) x (hip - ankle))``, the leg plane's
    normal: it comes from the foot, so a straight knee (thigh parallel to shank) is no special
    case. The thigh's and shank's y axes run up the bones, the foot's and toe's x axes forward.
    """
    hinge = _unit(_cross(points.metatarsal - points.heel, points.hip - points.ankle),
                  "legs: the leg plane (foot axis parallel to ankle-hip)")
    return {"thigh": _frame_from_y(_unit(points.hip - points.knee, "legs: hip-knee"), hinge),
            "shank": _frame_from_y(_unit(points.knee - points.ankle, "legs: knee-ankle"), hinge),
            "foot": _frame_from_x(_unit(points.metatarsal - points.heel, "legs: heel-metatarsal"),
                                  hinge),
            "toe": _frame_from_x(_unit(points.toe - points.metatarsal, "legs: metatarsal-toe"),
                                 hinge)}


def upper_body_angles(upper_body: UpperBody, n: int) -> dict:
    """Angle name -> shape (n,) for the spine, head and arms: the trunk totals times the weights
    (so the lumbar flexion angles sum to trunk_flexion, and so on), the head and arm angles as
    given."""
    if not isinstance(upper_body, UpperBody):
        raise ValueError(f"upper_body: expected an UpperBody, got {type(upper_body).__name__}")
    totals = {f.name: _per_frame(getattr(upper_body, f.name), f"upper_body.{f.name}", n)
              for f in fields(UpperBody) if not f.name.startswith(("shoulder", "elbow"))}
    angles = {}
    for name in VERTEBRAE:
        if name in LUMBAR:
            angles[f"{name}_flexion"] = FLEXION_WEIGHTS[name] * totals["trunk_flexion"]
            angles[f"{name}_bending"] = BENDING_WEIGHTS[name] * totals["trunk_bending"]
        if name != "C1":
            angles[f"{name}_rotation"] = ROTATION_WEIGHTS[name] * totals["trunk_rotation"]
    angles["C1_flexion"] = totals["head_flexion"]
    angles["C1_rotation"] = totals["head_rotation"]
    for field_name, joint, angle in (("shoulder_flexion", "shoulder", "flexion"),
                                     ("shoulder_abduction", "shoulder", "abduction"),
                                     ("elbow_flexion", "elbow", "flexion")):
        per_side = getattr(upper_body, field_name)
        if not isinstance(per_side, dict) or set(per_side) != {"right", "left"}:
            raise ValueError(f"upper_body.{field_name}: expected a dict with keys 'right' and 'left'")
        for s, side in SIDES:
            angles[f"{s}_{joint}_{angle}"] = _per_frame(per_side[side],
                                                        f"upper_body.{field_name}[{side!r}]", n)
    return angles


def skeleton_angles(body: Body, pelvis_center: np.ndarray, pelvis_angles: np.ndarray, legs: dict,
                    upper_body: UpperBody) -> np.ndarray:
    """The 56 angles shape (n, 56) in ANGLE_NAMES order (rad).

    ``pelvis_center`` shape (n, 3) (m) is the skeleton's root position; ``pelvis_angles`` shape
    (n, 3) its tilt, list and rotation; ``legs`` maps "right" and "left" to :class:`LegPoints`,
    whose hips must be where the pelvis puts them (to HIP_TOLERANCE_M); ``upper_body`` gives the
    totals spread by :func:`upper_body_angles`.
    """
    centre = frames_array(pelvis_center, "pelvis_center", 3)
    n = centre.shape[0]
    tilt_list_rotation = frames_array(pelvis_angles, "pelvis_angles", 3, n)
    if not isinstance(legs, dict) or set(legs) != {"right", "left"}:
        raise ValueError("legs: expected a dict with keys 'right' and 'left'")
    pelvis = pelvis_rotations(tilt_list_rotation)
    hips = hip_positions(body, centre, tilt_list_rotation)
    out = np.empty((n, len(ANGLE_NAMES)))
    for k, name in enumerate(("pelvis_tilt", "pelvis_list", "pelvis_rotation")):
        out[:, _COLUMN[name]] = tilt_list_rotation[:, k]
    for s, side in SIDES:
        points = legs[side]
        if not isinstance(points, LegPoints):
            raise ValueError(f"legs[{side!r}]: expected LegPoints, got {type(points).__name__}")
        points = LegPoints(**{f.name: frames_array(getattr(points, f.name), f"legs[{side!r}].{f.name}", 3, n)
                              for f in fields(LegPoints)})
        miss = np.linalg.norm(points.hip - hips[side], axis=1)
        if np.any(miss > HIP_TOLERANCE_M):
            frame = int(np.argmax(miss))
            raise ValueError(f"legs[{side!r}].hip: {miss[frame]:.3g} m from the pelvis's {side} hip "
                             f"in frame {frame} (allowed {HIP_TOLERANCE_M} m)")
        segments = leg_segment_rotations(points)
        # the world-axis angles, turned into clinical ones by the joints' own signs
        hip_axes = zxy_angles(np.swapaxes(pelvis, -1, -2) @ segments["thigh"])
        hinges = {"knee": _hinge_angle(segments["thigh"], segments["shank"]),
                  "ankle": _hinge_angle(segments["shank"], segments["foot"]),
                  "toes": _hinge_angle(segments["foot"], segments["toe"])}
        hip = _JOINT[f"{s}_hip"]
        for name, sign, value in zip(hip.angle_names, hip.signs, hip_axes):
            out[:, _COLUMN[name]] = sign * value
        for joint, value in hinges.items():
            hinge = _JOINT[f"{s}_{joint}"]
            out[:, _COLUMN[hinge.angle_names[0]]] = hinge.signs[0] * value
    for name, values in upper_body_angles(upper_body, n).items():
        out[:, _COLUMN[name]] = values
    return out
