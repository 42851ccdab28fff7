"""The 37-joint skeleton with 56 angles of the paper's body model (section 4, docs/skeleton.md).

"56 angles for the 37 joints of the body model -- 24 of these joints model the vertebrae in the
spine -- plus a position vector." This module fixes the joints, their rest offsets (from
:class:`klaw_ocp.body.Body` and the proportions below), the angle names and signs, and the forward
kinematics. :mod:`.pose` is its inverse for the legs.

World frame: x forward, y up, z to the right (right-handed), the soles at y = 0 in the rest pose.

Rotation convention: a joint's local rotation is ``Rz(sz*a_z) @ Rx(sx*a_x) @ Ry(sy*a_y)`` (intrinsic
Z, then X, then Y; a BVH ``Zrotation Xrotation Yrotation`` channel order), where ``a_z`` is the
joint's flexion-type angle, ``a_x`` its adduction/list/bending/abduction angle, ``a_y`` its
rotation angle and the signs ``s`` make every angle's positive sense the clinical one (flexion
positive). A joint with fewer angles uses the subset. World rotations compose parent first:
``R_world(child) = R_world(parent) @ R_local(child)`` and
``p(child) = p(parent) + R_world(parent) @ rest_offset(child)``.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import lru_cache
from typing import Callable

import numpy as np

from ..body import Body

# Proportions of body height H not in Table B-1. Winter, "Biomechanics and Motor Control of Human
# Movement" (4th ed., fig. 4.1, after Drillis & Contini 1966): shoulder joint 0.818 H, biacromial
# width 0.259 H, upper arm 0.186 H, forearm 0.146 H, hand 0.108 H, top of head 1.0 H. The spinal
# levels are our choice, rounded: L5/S1 a little above the hip line, C7/T1 at 0.83 H (the cervicale,
# C7's spinous process, is about 0.84 H, its body a little higher and further forward), the head's
# joint (atlanto-occipital/atlanto-axial) at 0.90 H between chin (0.870 H) and eye (0.936 H). The
# lumbar:thoracic split follows the regions' typical lengths (about 18 cm : 28 cm). The spine's
# joint column is straight and vertical in the rest pose: its curvature is not modelled.
L5_S1_LEVEL = 0.600
T12_L1_LEVEL = 0.690
C7_T1_LEVEL = 0.830
HEAD_JOINT_LEVEL = 0.900
SHOULDER_LEVEL = 0.818
BIACROMIAL_WIDTH = 0.259
UPPER_ARM = 0.186
FOREARM = 0.146
HAND = 0.108

LUMBAR = ("L5", "L4", "L3", "L2", "L1")
THORACIC = ("T12", "T11", "T10", "T9", "T8", "T7", "T6", "T5", "T4", "T3", "T2", "T1")
CERVICAL = ("C7", "C6", "C5", "C4", "C3", "C2", "C1")
#: The 24 vertebral joints, from the pelvis upward. The joint named after a vertebra is the motion
#: segment below it (the vertebra's rotation relative to the one below, at the disc between them);
#: C1 carries the head (nod at the atlanto-occipital joint, turn at the atlanto-axial joint).
VERTEBRAE = LUMBAR + THORACIC + CERVICAL
#: The joint-name prefix of each side, and the side's name in dicts keyed by side.
SIDES = (("r", "right"), ("l", "left"))


@dataclass(frozen=True)
class Dimensions:
    """The skeleton's lengths (m) for one body: Table B-1 for the legs, the proportions above for
    the rest. Vertical units are the rest distances between consecutive vertebral joints."""
    pelvis_width: float
    thigh: float
    shank: float
    ankle_height: float
    heel_back: float
    metatarsal_forward: float
    toe_length: float
    hip_height: float
    l5_above_hip: float
    lumbar_unit: float
    thoracic_unit: float
    cervical_unit: float
    head_top_above_c1: float
    shoulder_above_t1: float
    shoulder_half_width: float
    upper_arm: float
    forearm: float
    hand: float

    @classmethod
    def of(cls, body: Body) -> "Dimensions":
        if not isinstance(body, Body):
            raise ValueError(f"body: expected a klaw_ocp.body.Body, got {type(body).__name__}")
        h = body.height
        hip_height = body.l3 + body.l4 + body.l9
        thoracic_unit = (C7_T1_LEVEL - T12_L1_LEVEL) * h / len(THORACIC)
        t1_t2_level = C7_T1_LEVEL * h - thoracic_unit
        return cls(pelvis_width=body.l0, thigh=body.l3, shank=body.l4, ankle_height=body.l9,
                   heel_back=body.l8, metatarsal_forward=body.metatarsal_reach,
                   toe_length=body.l13, hip_height=hip_height,
                   l5_above_hip=L5_S1_LEVEL * h - hip_height,
                   lumbar_unit=(T12_L1_LEVEL - L5_S1_LEVEL) * h / len(LUMBAR),
                   thoracic_unit=thoracic_unit,
                   cervical_unit=(HEAD_JOINT_LEVEL - C7_T1_LEVEL) * h / (len(CERVICAL) - 1),
                   head_top_above_c1=(1.0 - HEAD_JOINT_LEVEL) * h,
                   shoulder_above_t1=SHOULDER_LEVEL * h - t1_t2_level,
                   shoulder_half_width=BIACROMIAL_WIDTH * h / 2, upper_arm=UPPER_ARM * h,
                   forearm=FOREARM * h, hand=HAND * h)


#: Elementary rotation axes in a joint's channel order.
AXIS_ORDER = ("z", "x", "y")


@dataclass(frozen=True)
class Joint:
    """One joint: its angles, in channel order Z, X, Y (a subset), each with the world-axis sign
    that makes the angle's positive sense the clinical one, and its rest offset from the parent
    joint in the parent's frame, ``offset(Dimensions) -> (x, y, z)`` in m."""
    name: str
    parent: str | None
    angle_names: tuple
    axes: tuple
    signs: tuple
    offset: Callable[[Dimensions], tuple]

    def rest_offset(self, body: Body) -> np.ndarray:
        """Shape (3,): the offset from the parent joint (zero for the root)."""
        return np.asarray(self.offset(Dimensions.of(body)), dtype=float)


def _leg(side: str) -> list:
    s = 1 if side == "r" else -1   # right leg at +z; adduction and rotation mirror
    return [
        Joint(f"{side}_hip", "pelvis",
              (f"{side}_hip_flexion", f"{side}_hip_adduction", f"{side}_hip_rotation"),
              ("z", "x", "y"), (1, s, s), lambda d: (0.0, 0.0, s * d.pelvis_width / 2)),
        Joint(f"{side}_knee", f"{side}_hip", (f"{side}_knee_flexion",), ("z",), (-1,),
              lambda d: (0.0, -d.thigh, 0.0)),
        Joint(f"{side}_ankle", f"{side}_knee", (f"{side}_ankle_dorsiflexion",), ("z",), (1,),
              lambda d: (0.0, -d.shank, 0.0)),
        Joint(f"{side}_toes", f"{side}_ankle", (f"{side}_toe_dorsiflexion",), ("z",), (1,),
              lambda d: (d.metatarsal_forward, -d.ankle_height, 0.0)),
    ]


def _arm(side: str) -> list:
    s = 1 if side == "r" else -1   # right arm at +z; abduction mirrors
    return [
        Joint(f"{side}_shoulder", "T1", (f"{side}_shoulder_flexion", f"{side}_shoulder_abduction"),
              ("z", "x"), (1, -s), lambda d: (0.0, d.shoulder_above_t1, s * d.shoulder_half_width)),
        Joint(f"{side}_elbow", f"{side}_shoulder", (f"{side}_elbow_flexion",), ("z",), (1,),
              lambda d: (0.0, -d.upper_arm, 0.0)),
    ]


def _spine() -> list:
    joints, parent = [], "pelvis"
    for name in VERTEBRAE:
        if name in LUMBAR:
            angles, axes, signs = (f"{name}_flexion", f"{name}_bending", f"{name}_rotation"), \
                ("z", "x", "y"), (-1, 1, 1)
        elif name == "C1":
            angles, axes, signs = ("C1_flexion", "C1_rotation"), ("z", "y"), (-1, 1)
        else:
            angles, axes, signs = (f"{name}_rotation",), ("y",), (1,)
        # each offset is the parent vertebra's height (body plus disc); L5's is from the hip line
        if parent == "pelvis":
            offset = lambda d: (0.0, d.l5_above_hip, 0.0)          # noqa: E731
        elif parent in LUMBAR:
            offset = lambda d: (0.0, d.lumbar_unit, 0.0)           # noqa: E731
        elif parent in THORACIC:
            offset = lambda d: (0.0, d.thoracic_unit, 0.0)         # noqa: E731
        else:
            offset = lambda d: (0.0, d.cervical_unit, 0.0)         # noqa: E731
        joints.append(Joint(name, parent, angles, axes, signs, offset))
        parent = name
    return joints


#: The 37 joints, every parent before its children. The root is the pelvis: its position is the
#: midpoint of the two hip joint centres; its angles are tilt (+ anterior), list (+ right side up)
#: and rotation (+ right hip forward).
JOINTS: tuple = tuple(
    [Joint("pelvis", None, ("pelvis_tilt", "pelvis_list", "pelvis_rotation"), ("z", "x", "y"),
           (-1, -1, 1), lambda d: (0.0, 0.0, 0.0))]
    + _leg("r") + _leg("l") + _spine() + _arm("r") + _arm("l"))

#: The 56 angle names in column order (angles.csv): joint by joint, each joint's in Z, X, Y order.
ANGLE_NAMES: tuple = tuple(a for j in JOINTS for a in j.angle_names)

#: End sites of the leaf joints, ``offset(Dimensions)`` in the leaf's frame: the toe tip, the top of
#: the head and the fingertips (the hand is not a separate segment; the wrist is a landmark).
END_SITES: dict = {
    "r_toes": lambda d: (d.toe_length, 0.0, 0.0),
    "l_toes": lambda d: (d.toe_length, 0.0, 0.0),
    "C1": lambda d: (0.0, d.head_top_above_c1, 0.0),
    "r_elbow": lambda d: (0.0, -(d.forearm + d.hand), 0.0),
    "l_elbow": lambda d: (0.0, -(d.forearm + d.hand), 0.0),
}

#: Landmarks that are not joints: (joint whose frame carries it, offset(Dimensions)).
LANDMARKS: dict = {
    "r_heel": ("r_ankle", lambda d: (-d.heel_back, -d.ankle_height, 0.0)),
    "l_heel": ("l_ankle", lambda d: (-d.heel_back, -d.ankle_height, 0.0)),
    "r_wrist": ("r_elbow", lambda d: (0.0, -d.forearm, 0.0)),
    "l_wrist": ("l_elbow", lambda d: (0.0, -d.forearm, 0.0)),
}

_JOINT_INDEX = {j.name: i for i, j in enumerate(JOINTS)}
_PARENT_INDEX = np.array([-1 if j.parent is None else _JOINT_INDEX[j.parent] for j in JOINTS])
# Where each of the 56 angles goes: its joint, its slot in (z, x, y) and its sign.
_ANGLE_JOINT = np.array([_JOINT_INDEX[j.name] for j in JOINTS for _ in j.angle_names])
_ANGLE_SLOT = np.array([AXIS_ORDER.index(ax) for j in JOINTS for ax in j.axes])
_ANGLE_SIGN = np.array([float(sg) for j in JOINTS for sg in j.signs])


def joint_index(name: str) -> int:
    """The joint's row in JOINTS and in every (n, 37, ...) array."""
    if name not in _JOINT_INDEX:
        raise ValueError(f"name: no joint called {name!r}; joints are {', '.join(_JOINT_INDEX)}")
    return _JOINT_INDEX[name]


def angle_index(name: str) -> int:
    """The angle's column in ANGLE_NAMES and in every (n, 56) array."""
    if name not in ANGLE_NAMES:
        raise ValueError(f"name: no angle called {name!r}")
    return ANGLE_NAMES.index(name)


def rest_offsets(body: Body) -> dict:
    """Joint name -> shape (3,) rest offset from its parent, in the parent's frame (m)."""
    d = Dimensions.of(body)
    return {j.name: np.asarray(j.offset(d), dtype=float) for j in JOINTS}


def end_site_offsets(body: Body) -> dict:
    """Leaf joint name -> shape (3,) end-site offset in the leaf's frame (m)."""
    d = Dimensions.of(body)
    return {name: np.asarray(f(d), dtype=float) for name, f in END_SITES.items()}


def rest_root_position(body: Body) -> np.ndarray:
    """Shape (3,): the pelvis centre standing upright with flat feet, soles at y = 0."""
    return np.array([0.0, Dimensions.of(body).hip_height, 0.0])


def segment_lengths(body: Body) -> dict:
    """Name -> length (m): each non-root joint's distance from its parent (the bone ending at it,
    e.g. ``r_knee`` = thigh = l3, ``r_toes`` = l12) and each end site's as ``<leaf>_end``
    (``r_toes_end`` = l13, ``C1_end`` = C1 to the top of the head)."""
    lengths = {name: float(np.linalg.norm(v)) for name, v in rest_offsets(body).items()
               if JOINTS[_JOINT_INDEX[name]].parent is not None}
    lengths.update({f"{name}_end": float(np.linalg.norm(v)) for name, v in end_site_offsets(body).items()})
    return lengths


def zxy_matrices(z: np.ndarray, x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """``Rz(z) @ Rx(x) @ Ry(y)`` for angles of any common shape S (rad); returns shape S + (3, 3)."""
    return _zxy_from_trig(np.cos(z), np.sin(z), np.cos(x), np.sin(x), np.cos(y), np.sin(y))


def _zxy_from_trig(cz, sz, cx, sx, cy, sy) -> np.ndarray:
    """:func:`zxy_matrices` from the angles' cosines and sines."""
    rows = ((cz * cy - sz * sx * sy, -sz * cx, cz * sy + sz * sx * cy),
            (sz * cy + cz * sx * sy, cz * cx, sz * sy - cz * sx * cy),
            (-cx * sy, sx, cx * cy))
    # written into place: nested np.stack cost more than the products (the body calls this a
    # few times for every step it hands out, the page's skeleton once more)
    out = np.empty(np.broadcast(cz, cx, cy).shape + (3, 3))
    for i, row in enumerate(rows):
        for j, value in enumerate(row):
            out[..., i, j] = value
    return out


def zxy_angles(rotation: np.ndarray) -> tuple:
    """The inverse of :func:`zxy_matrices`: rotations shape S + (3, 3) -> (z, x, y), each shape S,
    with x in [-pi/2, pi/2] (unique away from x = +-pi/2, where z and y share one axis)."""
    r = np.asarray(rotation, dtype=float)
    x = np.arctan2(r[..., 2, 1], np.hypot(r[..., 2, 0], r[..., 2, 2]))
    y = np.arctan2(-r[..., 2, 0], r[..., 2, 2])
    z = np.arctan2(-r[..., 0, 1], r[..., 1, 1])
    return z, x, y


def frames_array(value, name: str, columns: int, frames: int | None = None) -> np.ndarray:
    """``value`` as a finite float array of shape (frames, columns) (any number of frames when
    ``frames`` is None); a ValueError naming ``name`` otherwise."""
    a = np.asarray(value, dtype=float)
    if a.ndim != 2 or a.shape[1] != columns or (frames is not None and a.shape[0] != frames):
        raise ValueError(f"{name}: expected shape ({'n' if frames is None else frames}, {columns}), got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name}: contains NaN or infinite values")
    return a


def local_rotations(angles: np.ndarray) -> np.ndarray:
    """Angles shape (n, 56) in ANGLE_NAMES order (rad) -> local rotations shape (n, 37, 3, 3)."""
    a = frames_array(angles, "angles", len(ANGLE_NAMES))
    signed = a * _ANGLE_SIGN
    # the cosines and sines of the 56 angles only (not of 37 x 3): the joints' other axes are at 0,
    # whose cosine is 1 and sine 0
    cos, sin = np.ones((a.shape[0], len(JOINTS), 3)), np.zeros((a.shape[0], len(JOINTS), 3))
    cos[:, _ANGLE_JOINT, _ANGLE_SLOT], sin[:, _ANGLE_JOINT, _ANGLE_SLOT] = np.cos(signed), np.sin(signed)
    return _zxy_from_trig(cos[..., 0], sin[..., 0], cos[..., 1], sin[..., 1], cos[..., 2], sin[..., 2])


@dataclass(frozen=True)
class SkeletonFrames:
    """The skeleton over n frames, in the world frame (m).

    ``positions`` shape (n, 37, 3) and ``rotations`` shape (n, 37, 3, 3) are indexed like JOINTS;
    ``end_sites`` maps each leaf joint (END_SITES) and ``landmarks`` each LANDMARKS name (heels,
    wrists) to shape (n, 3).
    """
    positions: np.ndarray
    rotations: np.ndarray
    end_sites: dict
    landmarks: dict

    def position(self, name: str) -> np.ndarray:
        """Shape (n, 3): a joint's world position."""
        return self.positions[:, joint_index(name)]

    def rotation(self, name: str) -> np.ndarray:
        """Shape (n, 3, 3): a joint's world rotation (its frame's axes as columns)."""
        return self.rotations[:, joint_index(name)]


def _depth_levels() -> list:
    """The non-root joints level by level, each level after its parents': (joints, their parents),
    ints where a level has one joint (the spine's), index arrays where it has several (the legs')."""
    depth = [0] * len(JOINTS)
    for i in range(1, len(JOINTS)):
        depth[i] = depth[_PARENT_INDEX[i]] + 1
    levels = []
    for d in range(1, max(depth) + 1):
        joints = [i for i in range(len(JOINTS)) if depth[i] == d]
        levels.append((joints[0], int(_PARENT_INDEX[joints[0]])) if len(joints) == 1
                      else (np.array(joints), _PARENT_INDEX[joints]))
    return levels


_LEVELS = _depth_levels()


#: the joints that carry the end sites, then the landmarks
_CARRIERS = [_JOINT_INDEX[joint] for joint in END_SITES] + [_JOINT_INDEX[joint] for joint, _ in LANDMARKS.values()]


@lru_cache(maxsize=16)
def _fk_offsets(body: Body) -> tuple[np.ndarray, np.ndarray]:
    """The joints' offsets (37, 3), then the end sites' and landmarks' from their carriers, of a
    body: the same at every frame of every step (read-only: cached and shared)."""
    d = Dimensions.of(body)
    offsets = np.array([j.offset(d) for j in JOINTS], dtype=float)
    carried = np.array([f(d) for f in END_SITES.values()] + [f(d) for _, f in LANDMARKS.values()], dtype=float)
    offsets.flags.writeable = carried.flags.writeable = False
    return offsets, carried


def kinematic_tables(body: Body) -> dict:
    """What :func:`forward_kinematics` reads besides a frame's root and angles, for another
    implementation of it (the playground page's): each joint's rest offset from its parent (37, 3;
    the root's zero), each end site's from its joint (END_SITES order), and each of the 56 angles'
    joint, slot in the joint's Z, X, Y order (0, 1, 2) and sign."""
    offsets, carried = _fk_offsets(body)
    return {"offsets": offsets, "end_site_offsets": carried[:len(END_SITES)], "angle_joint": _ANGLE_JOINT,
            "angle_slot": _ANGLE_SLOT, "angle_sign": _ANGLE_SIGN}


def forward_kinematics(body: Body, root_position: np.ndarray, angles: np.ndarray) -> SkeletonFrames:
    """World joint positions and rotations from the pelvis centre shape (n, 3) and the angles
    shape (n, 56) (rad)."""
    root = frames_array(root_position, "root_position", 3)
    local = local_rotations(angles)
    if local.shape[0] != root.shape[0]:
        raise ValueError(f"root_position: {root.shape[0]} frames but angles has {local.shape[0]}")
    offsets, carried_offsets = _fk_offsets(body) if isinstance(body, Body) else _fk_offsets.__wrapped__(body)
    positions = np.empty((root.shape[0], len(JOINTS), 3))
    rotations = np.empty_like(local)
    positions[:, 0], rotations[:, 0] = root, local[:, 0]
    # level by level (the spine is a 24-deep chain, so the legs' and arms' joints at the same depth
    # are all the batching there is); each joint's rotation and offset products are those of a
    # joint at a time (numpy's matmul of each 3 x 3 in a batch is that of one alone)
    for joints, parents in _LEVELS:
        if isinstance(joints, int):    # the spine's: the product written in place (its own matmul)
            np.matmul(rotations[:, parents], local[:, joints], out=rotations[:, joints])
        else:
            rotations[:, joints] = rotations[:, parents] @ local[:, joints]
    # every joint's offset turned by its parent's rotation in one product, then the sums down the chains
    turned = (rotations[:, _PARENT_INDEX[1:]] @ offsets[1:, :, None])[..., 0]
    for joints, parents in _LEVELS:
        if isinstance(joints, int):
            np.add(positions[:, parents], turned[:, joints - 1], out=positions[:, joints])
        else:
            positions[:, joints] = positions[:, parents] + turned[:, joints - 1]
    # the end sites and landmarks: their joints' positions plus their offsets turned, in one product
    carried = positions[:, _CARRIERS] + (rotations[:, _CARRIERS] @ carried_offsets[:, :, None])[..., 0]
    end_sites = {name: carried[:, k] for k, name in enumerate(END_SITES)}
    landmarks = {name: carried[:, len(END_SITES) + k] for k, name in enumerate(LANDMARKS)}
    return SkeletonFrames(positions, rotations, end_sites, landmarks)
