"""``walk.bvh``: the 37-joint skeleton's motion as a Biovision Hierarchy file, and a small reader.

The writer turns angles.csv's table (time, the root position in m, the 56 angles in degrees,
docs/body.md) and the body (the rest offsets, :mod:`klaw_ocp.body_motion.skeleton`) into a BVH file
that Blender's bundled importer (``io_anim_bvh``) reads with its default axes (docs/animation.md).
The reader (:func:`read_bvh`) parses such a file back and does its forward kinematics, so that
tests can check that the file reproduces the skeleton.

**Axes.** Our world is x forward, y up, z right; BVH's is Y up, and the walk goes along +Z. The
proper rotation ``AXES`` maps a vector of ours to BVH: ``(X, Y, Z) = (-z, y, x)``, so BVH +X is the
walker's left, +Y up, +Z forward (right-handed, det +1). A rotation ``R`` of ours is
``AXES @ R @ AXES.T`` in BVH: a rotation by ``a`` about our z is one by ``-a`` about BVH X, about
our x one about BVH Z, about our y one about BVH Y. A joint's local rotation
``Rz(sz*az) @ Rx(sx*ax) @ Ry(sy*ay)`` (docs/skeleton.md) is therefore
``RX(-sz*az) @ RZ(sx*ax) @ RY(sy*ay)``: the channels ``Xrotation Zrotation Yrotation`` (the
skeleton's Z, X, Y order), with values ``-sz*az``, ``sx*ax``, ``sy*ay`` in degrees (``s`` the
joint's signs), and BVH's forward kinematics (intrinsic rotations in channel order, parent first)
gives ``AXES @ p`` for every joint position ``p`` of the skeleton.

**Channels.** The root (pelvis) has ``Xposition Yposition Zposition Xrotation Zrotation
Yrotation``; every other joint the three rotation channels, with zeros for the angles it does not
have. Blender's importer cannot take fewer: it looks its Euler order up from the three rotation
channels (a joint with one or two raises ``KeyError``) and reads a missing channel from the frame
line's last value. The root's position channels are its absolute position (the pelvis centre);
its ``OFFSET`` is the rest position (standing, soles at height 0), which Blender uses for the rest
pose and replaces by the channels in the animation, as bvhio does too.

**Layout.** One token layout only (the one Blender's line-based reader needs): ``HIERARCHY`` on
the first line, ``ROOT name``/``JOINT name``, then ``{`` alone on the next line, ``OFFSET x y z``
on the next and ``CHANNELS n ...`` on the one after; ``End Site``, ``{``, ``OFFSET``, ``}`` for
every leaf; ``}`` alone on its line; then ``MOTION``, ``Frames: n``, ``Frame Time: dt`` (dt to 17
significant digits: 1/30 s reads back as exactly 30 fps) and one line of channel values per frame
(fixed point, 9 decimals: 1e-9 m and 1e-9 degrees). Units m and degrees.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path

import numpy as np

from ..body import Body
from ..body_motion.skeleton import (ANGLE_NAMES, JOINTS, end_site_offsets, rest_offsets,
                                    rest_root_position)
from .atomic import atomic_write_text
from .registry import RUN_FILES
from .tables import decimal_rows

#: The file ``klaw-ocp run`` writes.
BVH_FILE = RUN_FILES["bvh"].name
#: Our world (x forward, y up, z right) -> BVH (X left, Y up, Z forward): ``v_bvh = AXES @ v``.
AXES = np.array([[0.0, 0.0, -1.0], [0.0, 1.0, 0.0], [1.0, 0.0, 0.0]])
#: Each skeleton rotation axis -> (its BVH channel, the sign of the angle in it): AXES maps our
#: z to BVH -X, our x to BVH Z, our y to BVH Y.
CHANNEL_OF_AXIS = {"z": ("Xrotation", -1.0), "x": ("Zrotation", 1.0), "y": ("Yrotation", 1.0)}
#: Every joint's rotation channels: the skeleton's Z, X, Y order in BVH axes.
ROTATION_CHANNELS = tuple(CHANNEL_OF_AXIS[axis][0] for axis in ("z", "x", "y"))
POSITION_CHANNELS = ("Xposition", "Yposition", "Zposition")
#: The columns the writer reads (angles.csv's, docs/body.md).
TABLE_COLUMNS = ("time", "root_x", "root_y", "root_z") + ANGLE_NAMES
#: Decimals of the motion values and offsets (m, degrees).
DECIMALS = 9
#: How far (s) a frame's time may be from ``time[0] + k / fps``: BVH frames are equally spaced.
TIME_TOLERANCE_S = 1e-6
_INDENT = "\t"


# -- writing -----------------------------------------------------------------------------------------
def _as_body(body) -> Body:
    if isinstance(body, Body):
        return body
    if isinstance(body, dict) and "height" in body and "mass" in body:
        return Body(height=float(body["height"]), mass=float(body["mass"]))
    raise ValueError(f"body: expected a klaw_ocp.body.Body or a dict with height and mass "
                     f"(summary.json's body), got {type(body).__name__}")


def _table_body_fps(motion, body, fps) -> tuple[dict, Body, float | None]:
    """(angles.csv's columns, the body, the frame rate) from a RunData (its own rate unless
    ``fps`` is given), a BodyMotion or a table."""
    from .run_data import RunData
    if isinstance(motion, RunData):
        if motion.angles is None:
            raise ValueError(f"motion: the run {motion.name!r} has no angles (a results folder written "
                             f"before angles.csv was)")
        table, body = motion.angles, motion.body_model() if body is None else body
        fps = motion.fps if fps is None else fps
    elif hasattr(motion, "table") and callable(motion.table):     # body_motion.BodyMotion
        table = motion.table()
    elif isinstance(motion, dict):
        table = motion
    else:
        raise ValueError(f"motion: expected a RunData, a BodyMotion or angles.csv's columns (a dict), "
                         f"got {type(motion).__name__}")
    if body is None:
        raise ValueError("body: required unless motion is a RunData (whose summary has the body)")
    missing = [c for c in TABLE_COLUMNS if c not in table]
    if missing:
        raise ValueError(f"motion: missing column(s) {', '.join(missing[:5])}"
                         f"{' ...' if len(missing) > 5 else ''} (angles.csv's columns, docs/body.md)")
    return table, _as_body(body), fps


def _frame_rate(time: np.ndarray, fps) -> float:
    """``fps``, checked: a number > 0 that the frame times are equally spaced at (the run's own
    rate, never one guessed from the times)."""
    if fps is None:
        raise ValueError("fps: required unless motion is a RunData (which carries the rate it was built at)")
    if isinstance(fps, bool) or not isinstance(fps, (int, float, np.floating, np.integer)) \
            or not math.isfinite(fps) or fps <= 0:
        raise ValueError(f"fps: got {fps!r}, allowed a number > 0")
    fps = float(fps)
    off = np.abs(time - (time[0] + np.arange(len(time)) / fps)) if len(time) else np.zeros(0)
    if np.any(off > TIME_TOLERANCE_S):
        k = int(np.argmax(off))
        raise ValueError(f"motion: frame {k} is at {time[k]!r} s, not at time[0] + {k}/{fps:g} s: BVH "
                         f"frames are equally spaced")
    return fps


def channel_values(table: dict) -> np.ndarray:
    """The motion section's values, shape (n, 6 + 3 * 36): the root's position in BVH axes (m),
    then every joint's ``Xrotation Zrotation Yrotation`` (degrees) in JOINTS order."""
    columns = {name: np.asarray(table[name], dtype=float) for name in TABLE_COLUMNS}
    n = len(columns["time"])
    if any(c.shape != (n,) for c in columns.values()):
        raise ValueError("motion: the columns differ in length")
    if not all(np.all(np.isfinite(c)) for c in columns.values()):
        raise ValueError("motion: contains NaN or infinite values")
    root = np.column_stack([columns["root_x"], columns["root_y"], columns["root_z"]]) if n else np.zeros((0, 3))
    out = np.zeros((n, 3 + 3 * len(JOINTS)))
    out[:, :3] = root @ AXES.T
    for j, joint in enumerate(JOINTS):
        for name, axis, sign in zip(joint.angle_names, joint.axes, joint.signs):
            channel, bvh_sign = CHANNEL_OF_AXIS[axis]
            out[:, 3 + 3 * j + ROTATION_CHANNELS.index(channel)] = bvh_sign * sign * columns[name]
    return out


def _vector(v) -> str:
    return " ".join(f"{x:.{DECIMALS}f}" for x in np.round(np.asarray(v, dtype=float), DECIMALS) + 0.0)


def hierarchy_text(body: Body) -> str:
    """The HIERARCHY section of ``body``'s skeleton (rest offsets in BVH axes, m)."""
    offsets, ends = rest_offsets(body), end_site_offsets(body)
    children = {j.name: [c.name for c in JOINTS if c.parent == j.name] for j in JOINTS}
    lines = ["HIERARCHY"]

    def joint(name: str, depth: int) -> None:
        pad = _INDENT * depth
        is_root = depth == 0
        offset = rest_root_position(body) if is_root else offsets[name]
        channels = (POSITION_CHANNELS if is_root else ()) + ROTATION_CHANNELS
        lines.extend([f"{pad}{'ROOT' if is_root else 'JOINT'} {name}", f"{pad}{{",
                      f"{pad}{_INDENT}OFFSET {_vector(AXES @ offset)}",
                      f"{pad}{_INDENT}CHANNELS {len(channels)} {' '.join(channels)}"])
        for child in children[name]:
            joint(child, depth + 1)
        if not children[name]:
            inner = pad + _INDENT
            lines.extend([f"{inner}End Site", f"{inner}{{",
                          f"{inner}{_INDENT}OFFSET {_vector(AXES @ ends[name])}", f"{inner}}}"])
        lines.append(f"{pad}}}")

    joint(JOINTS[0].name, 0)
    return "\n".join(lines) + "\n"


def bvh_text(motion, body=None, fps: float | None = None) -> str:
    """The BVH file of ``motion`` as text.

    ``motion``: a :class:`~klaw_ocp.result_files.run_data.RunData` (its ``angles`` at its
    ``fps``; its summary's body unless ``body`` is given), a
    :class:`~klaw_ocp.body_motion.BodyMotion`, or angles.csv's columns as a dict (time in s,
    root_x/y/z in m, the 56 angles in degrees). ``body``: a :class:`~klaw_ocp.body.Body` or
    summary.json's body dict. ``fps``: the frame rate (``output.fps``), required unless
    ``motion`` is a RunData. The frames must be equally spaced at it.
    """
    table, body, fps = _table_body_fps(motion, body, fps)
    values = channel_values(table)
    rate = _frame_rate(np.asarray(table["time"], dtype=float), fps)
    # "%.17g": 1/30 s reads back as the double nearest 1/30 (Blender: 30 fps, fps_base 1)
    header = f"MOTION\nFrames: {len(values)}\nFrame Time: {1.0 / rate:.17g}\n"
    return hierarchy_text(body) + header + decimal_rows(values, DECIMALS, " ")


def bvh_file(run) -> bytes:
    """walk.bvh of a :class:`~.run_data.RunData`, at its frame rate (the registry's renderer)."""
    return bvh_text(run).encode("utf-8")


def write_bvh(path, motion, body=None, fps: float | None = None) -> Path:
    """Write :func:`bvh_text` to ``path`` atomically (a temporary file in the same folder, then a
    rename; the user's normal file mode); returns the path."""
    path = Path(path)
    atomic_write_text(path, bvh_text(motion, body, fps))
    return path


# -- reading -----------------------------------------------------------------------------------------
@dataclass(frozen=True)
class BvhJoint:
    """One joint of a BVH hierarchy: ``parent`` its index (-1 for the root), ``offset`` shape (3,),
    ``channels`` its channel names, ``end_site`` shape (3,) or None."""
    name: str
    parent: int
    offset: np.ndarray
    channels: tuple
    end_site: np.ndarray | None


@dataclass(frozen=True)
class Bvh:
    """A parsed BVH file: ``joints`` in file order, ``frame_time`` (s), ``motion`` shape
    (frames, channels)."""
    joints: tuple
    frame_time: float
    motion: np.ndarray

    @property
    def names(self) -> list:
        return [j.name for j in self.joints]

    @property
    def frames(self) -> int:
        return self.motion.shape[0]

    def channel_columns(self) -> list:
        """Per joint: the column of each of its channels in ``motion``."""
        out, start = [], 0
        for joint in self.joints:
            out.append(list(range(start, start + len(joint.channels))))
            start += len(joint.channels)
        return out

    def forward_kinematics(self, frames=None) -> tuple[np.ndarray, dict]:
        """World joint positions shape (n, joints, 3) and end-site positions (leaf name -> (n, 3))
        at ``frames`` (indices; default all), in the file's axes.

        Rotation channels compose intrinsically in their listed order (``Zrotation Xrotation``
        is ``RZ @ RX``); a joint's position channels replace its offset (the root's absolute
        position, as Blender and bvhio read it); a child is at ``p_parent + R_parent @ offset``."""
        rows = self.motion if frames is None else self.motion[np.atleast_1d(frames)]
        n = rows.shape[0]
        positions = np.empty((n, len(self.joints), 3))
        rotations = np.empty((n, len(self.joints), 3, 3))
        ends = {}
        for j, (joint, cols) in enumerate(zip(self.joints, self.channel_columns())):
            local_r = np.broadcast_to(np.eye(3), (n, 3, 3)).copy()
            translation = np.broadcast_to(joint.offset, (n, 3)).copy()
            for name, c in zip(joint.channels, cols):
                axis = "XYZ".index(name[0])
                if name.endswith("position"):
                    translation[:, axis] = rows[:, c]
                else:
                    local_r = local_r @ _elementary(axis, np.radians(rows[:, c]))
            if joint.parent < 0:
                positions[:, j], rotations[:, j] = translation, local_r
            else:
                p = joint.parent
                positions[:, j] = positions[:, p] + np.einsum("nij,nj->ni", rotations[:, p], translation)
                rotations[:, j] = rotations[:, p] @ local_r
            if joint.end_site is not None:
                ends[joint.name] = positions[:, j] + rotations[:, j] @ joint.end_site
        return positions, ends


def _elementary(axis: int, angle: np.ndarray) -> np.ndarray:
    """Rotations about X (0), Y (1) or Z (2) by ``angle`` shape (n,) (rad): shape (n, 3, 3)."""
    c, s = np.cos(angle), np.sin(angle)
    r = np.zeros((len(angle), 3, 3))
    i, k = [(1, 2), (2, 0), (0, 1)][axis]
    r[:, axis, axis] = 1.0
    r[:, i, i], r[:, i, k], r[:, k, i], r[:, k, k] = c, -s, s, c
    return r


_CHANNELS = {f"{a}{kind}" for a in "XYZ" for kind in ("position", "rotation")}


def read_bvh(source) -> Bvh:
    """Parse a BVH file (a path, or its text when ``source`` is a str containing a newline) in the
    strict layout this module writes (module docstring); ValueError naming the line otherwise."""
    text = source if isinstance(source, str) and "\n" in source else Path(source).read_text(encoding="utf-8")
    lines = [(k + 1, line.split()) for k, line in enumerate(text.splitlines()) if line.strip()]
    pos = 0

    def take(expect: str | None = None, length: int | None = None) -> list:
        nonlocal pos
        if pos >= len(lines):
            raise ValueError(f"BVH: ended early (expected {expect or 'more'})")
        number, tokens = lines[pos]
        if expect is not None and tokens[0] != expect:
            raise ValueError(f"BVH line {number}: expected {expect!r}, got {' '.join(tokens)!r}")
        if length is not None and len(tokens) != length:
            raise ValueError(f"BVH line {number}: expected {length} tokens, got {' '.join(tokens)!r}")
        pos += 1
        return tokens

    def vector(tokens: list) -> np.ndarray:
        return np.array([float(v) for v in tokens[1:]], dtype=float)

    take("HIERARCHY", 1)
    joints: list = []

    def joint(keyword: str, parent: int) -> None:
        name = take(keyword, 2)[1]
        take("{", 1)
        offset = vector(take("OFFSET", 4))
        channels = take("CHANNELS")
        count = int(channels[1])
        if count != len(channels) - 2 or not set(channels[2:]) <= _CHANNELS:
            raise ValueError(f"BVH line {lines[pos - 1][0]}: bad CHANNELS of {name!r}")
        index = len(joints)
        joints.append([name, parent, offset, tuple(channels[2:]), None])
        children = 0
        while True:
            head = lines[pos][1] if pos < len(lines) else ["<end of file>"]
            if head[0] == "JOINT":
                joint("JOINT", index)
                children += 1
            elif head == ["End", "Site"]:
                take("End", 2)
                take("{", 1)
                joints[index][4] = vector(take("OFFSET", 4))
                take("}", 1)
            elif head == ["}"]:
                take("}", 1)
                break
            else:
                raise ValueError(f"BVH line {lines[pos][0] if pos < len(lines) else '?'}: expected JOINT, "
                                 f"End Site or '}}' in {name!r}, got {' '.join(head)!r}")
        if children == 0 and joints[index][4] is None:
            raise ValueError(f"BVH: the leaf joint {name!r} has no End Site")

    joint("ROOT", -1)
    take("MOTION", 1)
    frames = int(take("Frames:", 2)[1])
    tokens = take("Frame", 3)
    if tokens[1] != "Time:":
        raise ValueError(f"BVH line {lines[pos - 1][0]}: expected 'Frame Time: dt'")
    frame_time = float(tokens[2])
    width = sum(len(j[3]) for j in joints)
    motion = np.zeros((frames, width))
    for k in range(frames):
        motion[k] = [float(v) for v in take(length=width)]
    if pos != len(lines):
        raise ValueError(f"BVH line {lines[pos][0]}: more lines than Frames: {frames}")
    return Bvh(tuple(BvhJoint(n, p, o, c, e) for n, p, o, c, e in joints), frame_time, motion)
