"""The skeleton's 56 angles from world geometry: the inverse of :mod:`.skeleton` (docs/skeleton.md).

The legs come as world points (hip, knee, ankle, heel, first metatarsal head, toe tip) from the
virtual leg and the swing dynamics; the pelvis as its centre and three angles (the determinants of
gait); the spine, head and arms as a few totals (:class:`UpperBody`) that this module spreads over
the 24 vertebrae.

Every array is over n frames; all angles are in radians with the signs of :mod:`.skeleton`.
"""
from __future__ import annotations

from dataclasses import dataclass, fields
from functools import lru_cache

import numpy as np

from ..body import Body
from .leg_angles import LEG_COLUMNS, NORM_CHECKS, leg_angles
from .skeleton import ANGLE_NAMES, JOINTS, LUMBAR, SIDES, VERTEBRAE, Dimensions, frames_array, zxy_matrices

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


_LEG_POINT_NAMES = tuple(f.name for f in fields(LegPoints))


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
    if not np.isfinite(a).all():    # (the method: np.all's Python wrapper cost more than the test)
        raise ValueError(f"{name}: contains NaN or infinite values")
    return np.full(n, a)   # a copy: the caller may write into the angles


def _pelvis_matrices(a: np.ndarray) -> np.ndarray:
    pelvis = JOINTS[0]
    return zxy_matrices(*(sign * a[:, k] for k, sign in enumerate(pelvis.signs)))


def pelvis_rotations(pelvis_angles: np.ndarray) -> np.ndarray:
    """Pelvis tilt, list, rotation shape (n, 3) (rad) -> its world rotation shape (n, 3, 3)."""
    return _pelvis_matrices(frames_array(pelvis_angles, "pelvis_angles", 3))


def _hip_offsets(body: Body) -> dict:
    d = Dimensions.of(body)
    return {side: np.asarray(_JOINT[f"{s}_hip"].offset(d), dtype=float) for s, side in SIDES}


@lru_cache(maxsize=16)
def _hip_offsets_flat(body: Body) -> np.ndarray:
    """The right and the left hip's offsets in one (6,) array (read-only: one per body, shared)."""
    offsets = _hip_offsets(body)
    flat = np.concatenate([offsets[side] for _, side in SIDES])
    flat.flags.writeable = False
    return flat


def hip_positions(body: Body, pelvis_center: np.ndarray, pelvis_angles: np.ndarray, rotation=None) -> dict:
    """"right"/"left" -> the hip joint centres shape (n, 3) that the pelvis pose places (m);
    ``rotation``: :func:`pelvis_rotations` of ``pelvis_angles`` when the caller has them."""
    centre = frames_array(pelvis_center, "pelvis_center", 3)
    rotation = pelvis_rotations(pelvis_angles) if rotation is None else rotation
    return {side: centre + rotation @ offset for side, offset in _hip_offsets(body).items()}


_ARMS = (("shoulder_flexion", "shoulder", "flexion"), ("shoulder_abduction", "shoulder", "abduction"),
         ("elbow_flexion", "elbow", "flexion"))
_TOTALS = tuple(f.name for f in fields(UpperBody) if not f.name.startswith(("shoulder", "elbow")))
#: what the upper body's angles read, in the order upper_body_angles checks them: the five totals,
#: then each arm field's right and left values
_SOURCES = _TOTALS + tuple((field_name, side) for field_name, _, _ in _ARMS for _, side in SIDES)


def _upper_body_layout() -> tuple:
    """upper_body_angles' names in its order, each one's source (an index into _SOURCES) and
    weight (1.0 where the angle is its source itself)."""
    layout = []
    for name in VERTEBRAE:
        if name in LUMBAR:
            layout += [(f"{name}_flexion", "trunk_flexion", FLEXION_WEIGHTS[name]),
                       (f"{name}_bending", "trunk_bending", BENDING_WEIGHTS[name])]
        if name != "C1":
            layout.append((f"{name}_rotation", "trunk_rotation", ROTATION_WEIGHTS[name]))
    layout += [("C1_flexion", "head_flexion", None), ("C1_rotation", "head_rotation", None)]
    layout += [(f"{s}_{joint}_{angle}", (field_name, side), None)
               for field_name, joint, angle in _ARMS for s, side in SIDES]
    names, sources, weights = zip(*layout)
    return names, [_SOURCES.index(source) for source in sources], weights


_UPPER_NAMES, _UPPER_SOURCES, _UPPER_WEIGHTS = _upper_body_layout()
_WEIGHTED = [i for i, w in enumerate(_UPPER_WEIGHTS) if w is not None]
_UNWEIGHTED = [i for i, w in enumerate(_UPPER_WEIGHTS) if w is None]
_WEIGHTS = np.array([_UPPER_WEIGHTS[i] for i in _WEIGHTED])
_UPPER_COLUMNS = np.array([_COLUMN[name] for name in _UPPER_NAMES])


def _upper_body_sources(upper_body: UpperBody, n: int) -> np.ndarray:
    """(n, len(_SOURCES)): the upper body's totals and arm angles per frame, each checked as
    _per_frame checks it (a scalar or shape (n,), finite; a ValueError naming the first that is not)."""
    if not isinstance(upper_body, UpperBody):
        raise ValueError(f"upper_body: expected an UpperBody, got {type(upper_body).__name__}")
    out = np.empty((n, len(_SOURCES)))
    for i, source in enumerate(_SOURCES):
        if isinstance(source, str):
            value = getattr(upper_body, source)
        else:
            per_side = getattr(upper_body, source[0])
            sided = isinstance(per_side, dict) and set(per_side) == {"right", "left"}
            value = per_side[source[1]] if sided else None
        a = np.asarray(value, dtype=float) if value is not None else None
        if a is None or a.ndim > 1 or (a.ndim == 1 and a.shape[0] != n):
            break
        out[:, i] = a
    else:
        if np.isfinite(out).all():
            return out
    # something is wrong: check one by one, in order, for the message (one finiteness test above
    # instead of eleven)
    for name in _TOTALS:
        _per_frame(getattr(upper_body, name), f"upper_body.{name}", n)
    for field_name, _, _ in _ARMS:
        per_side = getattr(upper_body, field_name)
        if not isinstance(per_side, dict) or set(per_side) != {"right", "left"}:
            raise ValueError(f"upper_body.{field_name}: expected a dict with keys 'right' and 'left'")
        for _, side in SIDES:
            _per_frame(per_side[side], f"upper_body.{field_name}[{side!r}]", n)
    raise AssertionError("unreachable: an upper body that failed its checks passed them one by one")


def _upper_body_values(upper_body: UpperBody, n: int) -> np.ndarray:
    """(n, len(_UPPER_NAMES)): upper_body_angles' values as columns, in one product for the spine."""
    sources = _upper_body_sources(upper_body, n)
    values = np.empty((n, len(_UPPER_NAMES)))
    values[:, _WEIGHTED] = sources[:, [_UPPER_SOURCES[i] for i in _WEIGHTED]] * _WEIGHTS
    values[:, _UNWEIGHTED] = sources[:, [_UPPER_SOURCES[i] for i in _UNWEIGHTED]]
    return values


def upper_body_angles(upper_body: UpperBody, n: int) -> dict:
    """Angle name -> shape (n,) for the spine, head and arms: the trunk totals times the weights
    (so the lumbar flexion angles sum to trunk_flexion, and so on), the head and arm angles as
    given."""
    return dict(zip(_UPPER_NAMES, _upper_body_values(upper_body, n).T.copy()))


def set_upper_body_angles(angles: np.ndarray, upper_body: UpperBody) -> None:
    """Write :func:`upper_body_angles` into their columns of ``angles`` (n, 56)."""
    angles[:, _UPPER_COLUMNS] = _upper_body_values(upper_body, angles.shape[0])


def skeleton_angles(body: Body, pelvis_center: np.ndarray, pelvis_angles: np.ndarray, legs: dict,
                    upper_body: UpperBody | None, pelvis_rotation: np.ndarray | None = None) -> np.ndarray:
    """The 56 angles shape (n, 56) in ANGLE_NAMES order (rad).

    ``pelvis_center`` shape (n, 3) (m) is the skeleton's root position; ``pelvis_angles`` shape
    (n, 3) its tilt, list and rotation; ``legs`` maps "right" and "left" to :class:`LegPoints`,
    whose hips must be where the pelvis puts them (to HIP_TOLERANCE_M); ``upper_body`` gives the
    totals spread by :func:`upper_body_angles` (None: those angles left 0, for a caller that fills
    them from the legs' angles); ``pelvis_rotation``: :func:`pelvis_rotations` of ``pelvis_angles``
    when the caller has them.
    """
    centre = frames_array(pelvis_center, "pelvis_center", 3)
    n = centre.shape[0]
    tilt_list_rotation = frames_array(pelvis_angles, "pelvis_angles", 3, n)
    if not isinstance(legs, dict) or set(legs) != {"right", "left"}:
        raise ValueError("legs: expected a dict with keys 'right' and 'left'")
    pelvis = _pelvis_matrices(tilt_list_rotation) if pelvis_rotation is None else pelvis_rotation
    out = np.zeros((n, len(ANGLE_NAMES)))
    for k, name in enumerate(("pelvis_tilt", "pelvis_list", "pelvis_rotation")):
        out[:, _COLUMN[name]] = tilt_list_rotation[:, k]
    # the legs' segment frames and angles, compiled (:mod:`.leg_angles`: the hinge axis from the
    # foot, so a straight knee is no special case; the hip's zxy angles against the pelvis)
    legs_out = leg_angles(pelvis, centre, _both_legs(legs, n), _hip_offsets_flat(body))
    for (_, side), side_miss in zip(SIDES, legs_out["miss"].T):
        if (side_miss > HIP_TOLERANCE_M).any():
            frame = int(np.argmax(side_miss))
            raise ValueError(f"legs[{side!r}].hip: {side_miss[frame]:.3g} m from the pelvis's {side} hip "
                             f"in frame {frame} (allowed {HIP_TOLERANCE_M} m)")
    _check_lengths(legs_out["norms"].reshape(n, 2, 9))
    out[:, LEG_COLUMNS] = legs_out["angles"]
    if upper_body is not None:
        set_upper_body_angles(out, upper_body)
    return out


def _check_lengths(norms: np.ndarray) -> None:
    """A ValueError naming the first of :data:`.leg_angles.NORM_CHECKS` whose vector has no
    length (below 1e-12) in some frame, and the frame where it is shortest; ``norms`` (n, 2, 9)."""
    if not (norms < 1e-12).any():
        return
    start = 0
    for name, count in NORM_CHECKS:
        group = norms[:, :, start:start + count]
        if (group < 1e-12).any():
            raise ValueError(f"{name}: zero length in frame {int(np.argmin(group.min(axis=(1, 2))))}")
        start += count


def _both_legs(legs: dict, n: int) -> np.ndarray:
    """Both legs' points in one array (side (right, left), point (LegPoints' order), frame, xyz),
    checked as frames_array checks them (one finiteness test, not twelve)."""
    for _, side in SIDES:
        if not isinstance(legs[side], LegPoints):
            raise ValueError(f"legs[{side!r}]: expected LegPoints, got {type(legs[side]).__name__}")
    names = _LEG_POINT_NAMES
    try:
        points = np.array([[getattr(legs[side], name) for name in names] for _, side in SIDES], dtype=float)
    except ValueError:      # points of different shapes
        points = None
    if points is None or points.shape != (2, len(names), n, 3) or not np.isfinite(points).all():
        # the first point that is not a finite (n, 3) array raises
        points = np.array([[frames_array(getattr(legs[side], name), f"legs[{side!r}].{name}", 3, n) for name in names]
                           for _, side in SIDES])
    return points
