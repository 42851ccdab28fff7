"""``walk.mot``: the body's motion as OpenSim coordinates, for the gait2392 and gait10dof18musc
models (issue #23; docs/opensim.md says how to load it and why each rule holds).

Input: the columns of angles.csv (:meth:`klaw_ocp.body_motion.BodyMotion.table`, or
``RunData.angles`` read back from a results folder): ``time`` (s), ``root_x/y/z`` (the pelvis
centre, m) and the 56 angles in degrees. Output: OpenSim's motion (Storage) format, version 1,
angles in degrees, tab separated, one row per frame, the 19 coordinates of :data:`COORDINATES`.

Both skeletons share their frame: x forward, y up, z to the right, and at all angles zero both
stand upright with every segment frame aligned with the pelvis's. Both compose a joint's three
rotations in the same body-fixed order (Z, then X, then Y: OpenSim's rotation1 (0 0 1), rotation2
(1 0 0), rotation3 (0 1 0)), so the pelvis and the hips map exactly, each angle with a sign:

- pelvis: ``pelvis_tilt = -tilt`` (OpenSim turns about +z, the front up, posterior tilt; ours is
  anterior), ``pelvis_list = -list`` (about +x, the right side down; ours is right side up),
  ``pelvis_rotation = +rotation`` (about +y, the front to the left, as ours);
- hips: the same three angles (flexion about +z, adduction about +x right / -x left, internal
  rotation about +y right / -y left in both);
- knees: ``knee_angle = -knee_flexion`` (about +z: positive moves the shank forward, extension);
- ankles: ``ankle_angle = +dorsiflexion`` (gait2392's axis is 12 degrees off z, see the docs);
- lumbar: gait2392's torso is one rigid body from the lumbar joint up (head, arms, trunk); its
  three coordinates (about +z extension, +x bending to the right, +y the front turning left) are
  the Z-X-Y angles of our thorax (the T1 frame, where the shoulders hang) relative to the pelvis,
  the product of the local rotations of L5 ... L1 and T12 ... T1.

The pelvis translations are the model's pelvis origin, not our pelvis centre: gait2392's hip
joint centres are at :data:`MODEL_HIP_CENTRE` in its pelvis frame, so the origin is the hip
midpoint minus that offset turned by the pelvis. The model's legs are shorter than ours (hip
0.880 m above the floor standing, ours 0.5207 H = 0.937 m at 1.8 m): every translation is scaled
by :func:`translation_scale` so that the model walks with its feet on the ground, the walk shrunk
to its size (time unchanged).
"""
from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from ..body import Body
from ..errors import one_line
from ..body_motion.skeleton import (ANGLE_NAMES, LUMBAR, THORACIC, frames_array, joint_index,
                                    local_rotations, rest_root_position, zxy_angles)
from .atomic import atomic_write_bytes
from .registry import RUN_FILES
from .tables import decimal_rows

#: The results file's name.
MOT_FILE = RUN_FILES["mot"].name

#: The coordinates written, in column order (gait2392's names; gait10dof18musc has the subset
#: pelvis_tilt, pelvis_tx, pelvis_ty, hip_flexion, knee_angle, ankle_angle and lumbar_extension).
COORDINATES = ("pelvis_tilt", "pelvis_list", "pelvis_rotation", "pelvis_tx", "pelvis_ty", "pelvis_tz",
               "hip_flexion_r", "hip_adduction_r", "hip_rotation_r", "knee_angle_r", "ankle_angle_r",
               "hip_flexion_l", "hip_adduction_l", "hip_rotation_l", "knee_angle_l", "ankle_angle_l",
               "lumbar_extension", "lumbar_bending", "lumbar_rotation", "mtp_angle_r", "mtp_angle_l")
#: The columns of walk.mot.
MOT_COLUMNS = ("time",) + COORDINATES

#: OpenSim coordinate -> (our angle, sign): the coordinate is sign * our angle, exactly.
ANGLE_MAP = {
    "pelvis_tilt": ("pelvis_tilt", -1.0),
    "pelvis_list": ("pelvis_list", -1.0),
    "pelvis_rotation": ("pelvis_rotation", 1.0),
    **{f"{c}_{s}": (f"{s}_{ours}", sign) for s in ("r", "l") for c, ours, sign in (
        ("hip_flexion", "hip_flexion", 1.0), ("hip_adduction", "hip_adduction", 1.0),
        ("hip_rotation", "hip_rotation", 1.0), ("knee_angle", "knee_flexion", -1.0),
        ("ankle_angle", "ankle_dorsiflexion", 1.0))},
}
#: The joints whose product is the torso relative to the pelvis (pelvis to T1, where the arms hang).
TORSO_JOINTS = LUMBAR + THORACIC

#: gait2392 / gait10dof18musc, unscaled (a 1.8 m, 75 kg subject): the right hip joint centre in
#: the pelvis frame, m (the left mirrors z); the pelvis origin is between the anterior superior
#: iliac spines.
MODEL_HIP_CENTRE = (-0.0707, -0.0661, 0.0835)
#: Unscaled, every coordinate 0: the hip joint centre's height above the lowest point of the foot
#: (the toes' bone; the heel's is 2.3 mm higher), m. The femur puts the knee 0.3958 m below the
#: hip (its spline at knee_angle 0), the tibia the ankle 0.43 m below the knee, and the foot's
#: lowest point is 0.0541 m below the ankle. The pelvis origin then stands at 0.946 m
#: (:data:`MODEL_PELVIS_HEIGHT`; the models' default pelvis_ty is 0.95).
MODEL_HIP_HEIGHT = 0.8799
MODEL_PELVIS_HEIGHT = MODEL_HIP_HEIGHT - MODEL_HIP_CENTRE[1]

#: Decimals of the values (1e-10 degrees, 1e-10 m).
MOT_DECIMALS = 10


def translation_scale(body: Body, model_scale: float = 1.0) -> float:
    """The factor on our root's translations: the model's standing hip height (the unscaled
    model's, times ``model_scale``) over ours (``l3 + l4 + l9``). With it the model stands on the
    ground at our rest pose and its stance feet stay (nearly) still."""
    return _checked_scale(model_scale) * MODEL_HIP_HEIGHT / float(rest_root_position(body)[1])


def mot_columns(table: dict, body: Body, model_scale: float = 1.0) -> dict:
    """walk.mot's columns (:data:`MOT_COLUMNS`, degrees and m) from angles.csv's (``table``) for a
    walk of ``body`` shown on gait2392 / gait10dof18musc scaled uniformly by ``model_scale``
    (1: unscaled, the 1.8 m model)."""
    k = translation_scale(body, model_scale)
    missing = [c for c in ("time", "root_x", "root_y", "root_z", *ANGLE_NAMES) if c not in table]
    if missing:
        raise ValueError(f"table: missing column(s) {', '.join(missing[:5])}"
                         f"{' ...' if len(missing) > 5 else ''}; expected angles.csv's columns")
    time = np.asarray(table["time"], dtype=float)
    if time.ndim != 1 or not np.all(np.isfinite(time)):
        raise ValueError(f"table['time']: expected finite values in one dimension, got shape {time.shape}")
    n = time.shape[0]
    root = frames_array(_stacked(table, ("root_x", "root_y", "root_z"), n), "root", 3, n)
    degrees = frames_array(_stacked(table, ANGLE_NAMES, n), "angles", len(ANGLE_NAMES), n)
    column = {a: degrees[:, i] for i, a in enumerate(ANGLE_NAMES)}

    out = {"time": time}
    for name in COORDINATES[:3]:
        ours, sign = ANGLE_MAP[name]
        out[name] = sign * column[ours]
    local = local_rotations(np.radians(degrees))
    # the pelvis's world rotation is its local one, the same in both models (Rz Rx Ry)
    hip_mid = np.array([MODEL_HIP_CENTRE[0], MODEL_HIP_CENTRE[1], 0.0]) * model_scale   # between the hips
    origin = k * root - local[:, joint_index("pelvis")] @ hip_mid
    out.update(pelvis_tx=origin[:, 0], pelvis_ty=origin[:, 1], pelvis_tz=origin[:, 2])
    for name in COORDINATES[6:16]:
        ours, sign = ANGLE_MAP[name]
        out[name] = sign * column[ours]
    torso = np.broadcast_to(np.eye(3), (n, 3, 3))
    for joint in TORSO_JOINTS:
        torso = torso @ local[:, joint_index(joint)]
    ext, bend, rot = (np.degrees(a) for a in zxy_angles(torso))
    out.update(lumbar_extension=ext, lumbar_bending=bend, lumbar_rotation=rot)
    # toes up is positive in both; gait2392's mtp axis is oblique (docs/opensim.md), but bending its
    # toes cuts their dip into the floor at push-off from 2.8 to 0.8 cm
    out.update(mtp_angle_r=column["r_toe_dorsiflexion"], mtp_angle_l=column["l_toe_dorsiflexion"])
    return {c: np.asarray(out[c], dtype=float) for c in MOT_COLUMNS}


def mot_text(table: dict, body: Body, model_scale: float = 1.0, name: str = "walk") -> str:
    """walk.mot's text: the Storage header (``name``, version=1, nRows, nColumns, inDegrees=yes,
    endheader), the column labels, then one tab-separated row per frame."""
    columns = mot_columns(table, body, model_scale)
    n = len(columns["time"])
    title = one_line(name) or "walk"
    head = (f"{title}\nversion=1\nnRows={n}\nnColumns={len(MOT_COLUMNS)}\ninDegrees=yes\nendheader\n"
            + "\t".join(MOT_COLUMNS) + "\n")
    return head + decimal_rows(np.column_stack([columns[c] for c in MOT_COLUMNS]), MOT_DECIMALS, "\t")


def render_mot(table: dict, body: Body, model_scale: float = 1.0, name: str = "walk") -> bytes:
    """:func:`mot_text` as UTF-8 bytes (for :func:`klaw_ocp.result_files.atomic.write_rendered`)."""
    return mot_text(table, body, model_scale, name).encode("utf-8")


def mot_file(run) -> bytes:
    """walk.mot of a :class:`~.run_data.RunData` on the unscaled models (the registry's renderer)."""
    return render_mot(run.angles, run.body_model(), name=run.summary.get("name", "walk"))


def write_mot(path, table: dict, body: Body, model_scale: float = 1.0, name: str = "walk") -> Path:
    """Write walk.mot (:func:`mot_text`) to ``path`` atomically; returns the path."""
    path = Path(path)
    atomic_write_bytes(path, render_mot(table, body, model_scale, name))
    return path


def _stacked(table: dict, names, n: int) -> np.ndarray:
    """Columns ``names`` of ``table`` as an (n, len(names)) float array; each must have n rows."""
    arrays = [np.asarray(table[c], dtype=float).reshape(-1) for c in names]
    short = [c for c, a in zip(names, arrays) if a.shape[0] != n]
    if short:
        raise ValueError(f"table: column(s) {', '.join(short[:5])} without the {n} rows of 'time'")
    return np.column_stack(arrays) if n else np.zeros((0, len(arrays)))


def _checked_scale(model_scale) -> float:
    if isinstance(model_scale, bool) or not isinstance(model_scale, (int, float)) \
            or not math.isfinite(model_scale) or model_scale <= 0:
        raise ValueError(f"model_scale: got {model_scale!r}, allowed a finite number > 0 "
                         f"(the model's uniform scale factor, 1 for the unscaled 1.8 m model)")
    return float(model_scale)
