"""The upper body follows the lower body (§2.4 principle 3) and the body's side-to-side weave
(§4.2, the determinant "lateral displacement"). docs/upper-body.md gives the rules, their sources
and the human reference values behind the numbers below.

Principle 3: "the angles of the arms as well as the rotations in the shoulder and spine which
compensate for pelvic movements are expressed as functions of the corresponding angles in the
lower body. The arms, for example, swing forward with the opposite legs."

Every function works on per-frame arrays (n,), vectorised over frames; angles in radians with the
signs of docs/skeleton.md (flexion positive; x forward, y up, z to the right).
"""
from __future__ import annotations

import math
from collections.abc import Sequence
from dataclasses import dataclass

import numpy as np

from .pose import ROTATION_WEIGHTS, UpperBody
from .skeleton import LUMBAR, THORACIC, frames_array

#: Where the lateral shift peaks, as a fraction of the single support after the hind leg's toe-off.
#: The paper: "a maximum shortly after toe-off"; in people the pelvis is furthest over the stance
#: foot around mid-stance, half-way through single support. A quarter honours "shortly" and leans
#: towards the human timing.
LATERAL_PEAK_SINGLE_SUPPORT_FRACTION = 0.25

#: The shoulder line (T1, which carries the shoulders) turns against the pelvis in the world by this
#: fraction of the pelvic rotation, so the shoulders turn opposite to the hips as in people.
THORAX_COUNTER_ROTATION = 0.5
#: The share of trunk_rotation that the joints up to T1 take (pose.ROTATION_WEIGHTS); the rest is
#: the neck's token share, which the head's own turn then takes back.
SHOULDER_ROTATION_SHARE = sum(ROTATION_WEIGHTS[v] for v in LUMBAR + THORACIC)

#: The hip half range at which the shoulder swings by exactly ``arm_swing_amplitude``: half the
#: ~40° sagittal hip range (10° extension to 30° flexion) of adults at a comfortable speed.
REFERENCE_HIP_HALF_RANGE = math.radians(20.0)
#: The shoulder's mean flexion: the arm swings about the hanging position.
SHOULDER_MEAN_FLEXION = 0.0
#: A small constant abduction so that the hands pass clear of the hips.
SHOULDER_ABDUCTION = math.radians(5.0)
#: Elbow flexion = base + share * (shoulder flexion - its mean), never below the minimum: with the
#: swing of ±20° (the default at about 6 km/h) the elbow goes from 18° at the back of the swing to 38° in front, as in
#: people (about 15-20° behind, 35-45° in front).
ELBOW_BASE_FLEXION = math.radians(28.0)
ELBOW_SHOULDER_SHARE = 0.5
ELBOW_MIN_FLEXION = math.radians(5.0)

_SIDES = ("right", "left")
_OTHER = {"right": "left", "left": "right"}


@dataclass(frozen=True)
class StepWindow:
    """One step of the walk as the upper body sees it."""
    t_start: float      # walk time (s) of this step's heel strike (its stance leg lands)
    t_step: float       # s; the next step's heel strike is at t_start + t_step
    t_ds: float         # s; the other (hind) leg's toe-off is at t_start + t_ds
    stance_side: str    # "right" or "left": the leg that lands at t_start
    moving: bool = True  # False for a step with step length 0 (a walk's closing step ending at rest)
    #: the step's pelvic_lateral_shift (m), where its attributes differ from the walk's; None: the walk's
    lateral_shift: float | None = None


def _vector(value, name: str, n: int | None = None) -> np.ndarray:
    """``value`` as a finite float array of shape (n,); a ValueError naming ``name`` otherwise."""
    a = np.asarray(value, dtype=float)
    if a.ndim != 1 or (n is not None and a.shape[0] != n):
        raise ValueError(f"{name}: expected shape ({'n' if n is None else n},), got {a.shape}")
    if not np.isfinite(a).all():
        raise ValueError(f"{name}: contains NaN or infinite values")
    return a


def _checked_steps(steps: Sequence[StepWindow]) -> list[StepWindow]:
    """The windows, checked: finite times, t_step > 0, 0 <= t_ds < t_step for a moving step (so the
    peak lies strictly inside the window), a known side, and no two windows overlapping."""
    checked = []
    for k, step in enumerate(steps):
        name = f"steps[{k}]"
        if not isinstance(step, StepWindow):
            raise ValueError(f"{name}: expected a StepWindow, got {type(step).__name__}")
        if step.stance_side not in _SIDES:
            raise ValueError(f"{name}.stance_side: expected 'right' or 'left', got {step.stance_side!r}")
        if not all(math.isfinite(v) for v in (step.t_start, step.t_step, step.t_ds)):
            raise ValueError(f"{name}: t_start, t_step and t_ds must be finite")
        if not step.t_step > 0.0:
            raise ValueError(f"{name}.t_step: expected > 0, got {step.t_step}")
        if step.moving and not 0.0 <= step.t_ds < step.t_step:
            raise ValueError(f"{name}.t_ds: expected 0 <= t_ds < t_step = {step.t_step}, got {step.t_ds}")
        checked.append(step)
    ordered = sorted(checked, key=lambda s: s.t_start)
    for before, after in zip(ordered, ordered[1:]):
        # the windows are summed, so an overlap would add two steps' shifts
        if after.t_start < before.t_start + before.t_step - 1e-9:
            raise ValueError(f"steps: the window starting at {after.t_start} s overlaps the one "
                             f"starting at {before.t_start} s (t_step {before.t_step} s)")
    return checked


def lateral_displacement(attrs, steps: Sequence[StepWindow], t: np.ndarray) -> np.ndarray:
    """The determinant 'lateral displacement' (§4.2): the pelvis centre's z (m, + to the right) at
    walk times t (n,), vectorised (no Python loop over frames; a loop over steps is fine).

    In each moving step: 0 at its heel strike, ``pelvic_lateral_shift`` towards the stance side at
    the peak (LATERAL_PEAK_SINGLE_SUPPORT_FRACTION of the single support after the hind leg's
    toe-off), 0 again at the next heel strike, linear in between ("linear interpolation is applied
    to obtain all the intermediate angles"). Still steps and times outside every window give 0, so
    the curve is continuous wherever the windows start and end.
    """
    time = _vector(t, "t")
    z = np.zeros_like(time)
    for step in _checked_steps(steps):
        # a step's own shift (its schedule's): the hat is 0 at both heel strikes, so the pelvis
        # moves on continuously where the shift changes from one step to the next
        shift = attrs.get("pelvic_lateral_shift") if step.lateral_shift is None else step.lateral_shift
        if not step.moving or shift == 0.0:
            continue
        toe_off = step.t_start + step.t_ds
        peak = toe_off + LATERAL_PEAK_SINGLE_SUPPORT_FRACTION * (step.t_step - step.t_ds)
        towards_stance = shift if step.stance_side == "right" else -shift
        # np.interp with zero ends is the hat function of this window, 0 outside it
        z += np.interp(time, [step.t_start, peak, step.t_start + step.t_step],
                       [0.0, towards_stance, 0.0], left=0.0, right=0.0)
    return z


def _arms(attrs, hips: dict, amplitude: np.ndarray | None = None) -> tuple[dict, dict, dict]:
    """Shoulder flexion, shoulder abduction and elbow flexion of each side (rad).

    Each shoulder swings with the difference of the hips, opposite hip minus own: forward as the
    opposite leg swings forward (principle 3), in antiphase with its own leg, about the same mean
    whatever the hips' mean flexion, and still when the legs stand side by side. Its half range is
    ``arm_swing_amplitude`` times the hips' half range over REFERENCE_HIP_HALF_RANGE, so shorter,
    slower steps swing the arms less, as in people. ``amplitude`` (rad, one per frame): where the
    walk's steps have their own ``arm_swing_amplitude`` (:func:`step_amplitudes`).
    """
    gain = (attrs.rad("arm_swing_amplitude") if amplitude is None else amplitude) / REFERENCE_HIP_HALF_RANGE
    shoulder, abduction, elbow = {}, {}, {}
    for side in _SIDES:
        swing = gain * 0.5 * (hips[_OTHER[side]] - hips[side])
        shoulder[side] = SHOULDER_MEAN_FLEXION + swing
        abduction[side] = np.full_like(swing, SHOULDER_ABDUCTION)
        # the elbow bends more as the arm comes forward; the floor keeps a very large swing from
        # straightening it (people do not lock the elbow when walking)
        elbow[side] = np.maximum(ELBOW_BASE_FLEXION + ELBOW_SHOULDER_SHARE * swing, ELBOW_MIN_FLEXION)
    return shoulder, abduction, elbow


def step_amplitudes(values: np.ndarray, step: np.ndarray, tau: np.ndarray, t_step: np.ndarray) -> np.ndarray:
    """A per-step value at frames (``step`` index into ``values`` (m,), ``tau`` s into that step
    of length ``t_step`` (m,)): step k's at its heel strike, moving to step k + 1's by the next on
    S(s) = 3s² − 2s³, whose rate is 0 at both ends, so a change from one step to the next never
    jumps an angle or its rate (a walk's last step keeps its own)."""
    values, step = np.asarray(values, float), np.asarray(step, int)
    following = values[np.minimum(step + 1, len(values) - 1)]
    s = np.clip(np.asarray(tau, float) / np.asarray(t_step, float)[step], 0.0, 1.0)
    return values[step] + (following - values[step]) * s * s * (3.0 - 2.0 * s)


def upper_body_motion(attrs, t: np.ndarray, trunk_lean: np.ndarray, hip_flexion: dict,
                      pelvis_angles: np.ndarray | None = None, arm_swing: np.ndarray | None = None) -> UpperBody:
    """trunk_lean: the dynamics' θ2 (n,) rad (> 0 leaning forward); hip_flexion: {"right": (n,), "left": (n,)}
    clinical hip flexion of each leg (rad, + thigh forward) at the same frames; pelvis_angles: (n, 3)
    tilt, list, rotation (rad, docs/skeleton.md signs), None = level and square; arm_swing: (n,)
    the arm swing amplitude (rad) at each frame, None = the attribute's. Returns pose.UpperBody.

    The trunk totals are relative to the pelvis and the head's to the top of the spine; they add
    to the pelvis angles plane by plane (exact when only one plane moves, first order otherwise,
    the pelvis angles being a few degrees):
    - trunk flexion θ2 - tilt, so the trunk's lean in the world is the dynamics' θ2;
    - trunk bending + list: a positive list (right hip up) tips the spine's base to the left, so
      bending to the right by the same angle keeps the trunk upright in the frontal plane;
    - trunk rotation -(1 + THORAX_COUNTER_ROTATION) * rotation / SHOULDER_ROTATION_SHARE: the
      shoulder line (T1) turns by -THORAX_COUNTER_ROTATION * rotation in the world;
    - head flexion -(tilt + trunk flexion) = -θ2 and head rotation -(rotation + trunk rotation):
      the head stays level and faces forward.
    """
    n = _vector(t, "t").shape[0]
    lean = _vector(trunk_lean, "trunk_lean", n)
    if not isinstance(hip_flexion, dict) or set(hip_flexion) != set(_SIDES):
        raise ValueError("hip_flexion: expected a dict with keys 'right' and 'left'")
    hips = {side: _vector(hip_flexion[side], f"hip_flexion[{side!r}]", n) for side in _SIDES}
    pelvis = np.zeros((n, 3)) if pelvis_angles is None else frames_array(pelvis_angles, "pelvis_angles", 3, n)
    tilt, list_angle, rotation_angle = pelvis.T

    trunk_flexion = lean - tilt
    trunk_bending = list_angle.copy()
    trunk_rotation = -(1.0 + THORAX_COUNTER_ROTATION) / SHOULDER_ROTATION_SHARE * rotation_angle
    head_flexion = -(tilt + trunk_flexion)
    head_rotation = -(rotation_angle + trunk_rotation)
    amplitude = None if arm_swing is None else _vector(arm_swing, "arm_swing", n)
    shoulder_flexion, shoulder_abduction, elbow_flexion = _arms(attrs, hips, amplitude)
    return UpperBody(trunk_flexion=trunk_flexion, trunk_bending=trunk_bending,
                     trunk_rotation=trunk_rotation, head_flexion=head_flexion,
                     head_rotation=head_rotation, shoulder_flexion=shoulder_flexion,
                     shoulder_abduction=shoulder_abduction, elbow_flexion=elbow_flexion)
