"""The human body on the simulated walk: the 37-joint skeleton's root and 56 angles at every frame
(section 4, principles 2 and 3; docs/body.md).

- Legs (principle 2): in stance the virtual leg (§4.2, :mod:`klaw_ocp.kinematics.virtual_leg`) on
  the simulated hip, from heel strike through the next step's double support to toe-off
  (:meth:`klaw_ocp.walk.Walk.stance_foot`); in swing the dynamics' θ3, θ4 with the kinematic swing
  foot (§4.3, :mod:`klaw_ocp.kinematics.swing_foot`) kept out of the ground (:mod:`.swing_foot_guard`).
- The planar model in 3D: the pelvis centre weaves sideways (the determinant "lateral
  displacement", :func:`.upper_body.lateral_displacement`), each foot walks along its own ground
  line, and each leg moves in the plane through its ground line and its hip (:class:`LegPlanes`).
- Pelvis (§4.2, the determinants): rotation and list about the stance hip, each step's
  :class:`klaw_ocp.kinematics.pelvis.PelvisSchedule` (the one its swing was solved with), no tilt;
  the stance leg hangs from the simulated hip, the other leg from the pelvis's other hip.
- Upper body (principle 3): :func:`.upper_body.upper_body_motion` from the dynamics' θ2 and the
  legs' hip flexion.

World frame: x forward, y up, z to the right; m, s, rad.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from ..gait.plan import stance_leg
from ..kinematics.leg_geometry import leg_ik
from ..kinematics.pelvis import PelvisSchedule
from .pose import LegPoints, UpperBody, hip_positions, skeleton_angles, upper_body_angles
from .skeleton import ANGLE_NAMES, SIDES
from .stance_legs import stance_frames
from .swing_legs import swing_legs
from .upper_body import StepWindow, lateral_displacement, step_amplitudes, upper_body_motion
from .walk_samples import frame_times, locate_steps, stance_at, stance_curves

#: The columns of angles.csv: time (s), the root (pelvis centre, m), then the 56 angles (degrees).
ANGLES_COLUMNS = ("time", "root_x", "root_y", "root_z") + ANGLE_NAMES
_POINTS = ("hip", "knee", "ankle", "heel", "metatarsal", "toe")
_FOOT = ("ankle", "heel", "metatarsal", "toe")
_OTHER = {"right": "left", "left": "right"}
_HIP_FLEXION = {side: ANGLE_NAMES.index(f"{s}_hip_flexion") for s, side in SIDES}


@dataclass(frozen=True)
class BodyMotion:
    """The body over n frames (world frame, m and rad)."""
    t: np.ndarray              # (n,) walk time, s
    root: np.ndarray           # (n, 3) pelvis centre
    pelvis_angles: np.ndarray  # (n, 3) tilt, list, rotation
    legs: dict                 # "right"/"left" -> pose.LegPoints, each point (n, 3)
    upper_body: UpperBody      # the spine, head and arm totals
    angles: np.ndarray         # (n, 56) in skeleton.ANGLE_NAMES order

    def table(self) -> dict:
        """angles.csv as columns (ANGLES_COLUMNS): time, root_x/y/z in m, the angles in degrees."""
        columns = {"time": self.t, "root_x": self.root[:, 0], "root_y": self.root[:, 1], "root_z": self.root[:, 2]}
        columns.update(zip(ANGLE_NAMES, np.degrees(self.angles).T + 0.0))    # + 0.0: no "-0" in the file
        return columns


@dataclass(frozen=True)
class Samples:
    """The frames the body is evaluated at."""
    t: np.ndarray        # walk time
    step: np.ndarray     # index of the step the frame belongs to
    tau: np.ndarray      # step-local time

    @classmethod
    def of(cls, walk, fps: float) -> "Samples":
        frames = frame_times(walk.duration, fps)
        return cls(frames, *locate_steps(walk.steps, frames))


@dataclass(frozen=True)
class LegPlanes:
    """The planar model in 3D. Each foot's centreline is its ground line (y = 0, z = z_foot, along
    x); each leg lives in the plane through its ground line and its hip, where the 2D geometry of
    the model holds: in-plane coordinates (x, v), v the distance from the ground line, are the
    world point (x, v·y_h/v_leg, z_foot + v·dz/v_leg), dz = z_hip − z_foot and v_leg = sqrt(y_h² +
    dz²) the hip's in-plane height. The map is an isometry, so every segment keeps its length, and
    v = 0 is the ground line, so a planted foot stays planted."""
    foot_z: dict         # side -> z of the foot's centreline (m)
    hips: dict           # side -> the hip joint centres (n, 3)

    def hip_in_plane(self, side: str) -> np.ndarray:
        """(n, 2): the hip's x and in-plane height v_leg."""
        hip = self.hips[side]
        return np.column_stack([hip[:, 0], np.hypot(hip[:, 1], hip[:, 2] - self.foot_z[side])])

    def to_world(self, side: str, points: np.ndarray, rows=slice(None)) -> np.ndarray:
        """In-plane points (n, 2) of the leg at ``rows`` of the samples -> world points (n, 3)."""
        hip, z_foot = self.hips[side][rows], self.foot_z[side]
        dz = hip[:, 2] - z_foot
        v_leg = np.hypot(hip[:, 1], dz)
        v = points[:, 1]
        return np.column_stack([points[:, 0], v * hip[:, 1] / v_leg, z_foot + v * dz / v_leg])

    def all_to_world(self, side: str, points: dict) -> dict:
        """:meth:`to_world` of several in-plane point arrays (n, 2) at every sample, in one pass
        (name -> world points (n, 3))."""
        hip, z_foot = self.hips[side], self.foot_z[side]
        dz = hip[:, 2] - z_foot
        v_leg = np.hypot(hip[:, 1], dz)
        p = np.stack(list(points.values()))
        v = p[..., 1]
        return dict(zip(points, np.stack([p[..., 0], v * hip[:, 1] / v_leg, z_foot + v * dz / v_leg], axis=-1)))


def step_windows(walk) -> list:
    """Each step as the upper body and the lateral displacement see it (:class:`.upper_body.StepWindow`)."""
    return [StepWindow(s.t_start, s.plan.timings.t_step, s.plan.timings.t_ds, stance_leg(s.index),
                       moving=s.plan.constraints.step_length != 0,
                       lateral_shift=s.plan.attributes.pelvic_lateral_shift)
            for s in walk.steps]


def arm_swing_at(walk, samples: Samples) -> np.ndarray | None:
    """The arm swing amplitude (rad) at the frames, where the walk's steps have amplitudes of their
    own (a schedule's), each reached at its step's heel strike (:func:`.upper_body.step_amplitudes`);
    None where every step has the walk's."""
    values = [s.plan.attributes.rad("arm_swing_amplitude") for s in walk.steps]
    if all(v == walk.spec.attributes.rad("arm_swing_amplitude") for v in values):
        return None
    return step_amplitudes(values, samples.step, samples.tau, [s.plan.timings.t_step for s in walk.steps])


@dataclass(frozen=True)
class WalkPieces:
    """What every evaluation of the pelvis and the legs' planes needs from the walk, gathered once
    (the body asks for the planes at the frames, at each step's toe-off and on the swing foot's
    guard grid)."""
    stance: object               # walk_samples.StepCurves of the stance
    windows: list                # step_windows
    stance_right: np.ndarray     # (steps,) bool
    starts: np.ndarray           # (steps,) each step's walk time at its heel strike

    @classmethod
    def of(cls, walk) -> "WalkPieces":
        return cls(stance_curves(walk), step_windows(walk),
                   np.array([stance_leg(k) == "right" for k in range(len(walk.steps))]),
                   np.array([s.t_start for s in walk.steps]))


def leg_planes(walk, samples: Samples, pelvis_angles: np.ndarray,
               pieces: WalkPieces | None = None) -> tuple[LegPlanes, np.ndarray, np.ndarray, np.ndarray]:
    """The pelvis and the legs' planes at the samples: (planes, pelvis centre (n, 3), lean θ2 (n,),
    the simulated hip (n, 2): x and height in the planar model).

    The simulated hip is the current step's stance hip, exact in its leg's plane: its in-plane
    height is the simulated height v, so its world height is sqrt(v² − dz²). The pelvis centre
    is then where the pelvis angles put it from that hip, at the lateral displacement's z; the
    other hip is where the pelvis puts it (:func:`.pose.hip_positions`)."""
    body, attrs = walk.spec.body, walk.spec.attributes
    pieces = WalkPieces.of(walk) if pieces is None else pieces
    n = len(samples.t)
    hip_sim, lean = stance_at(walk, pieces.stance, samples.step, samples.tau)
    half = attrs.foot_lateral_distance / 2    # the distance between the feet's centrelines
    foot_z = {"right": half, "left": -half}
    stance_right = pieces.stance_right[samples.step]
    offsets = hip_positions(body, np.zeros((n, 3)), pelvis_angles)     # each hip from the pelvis centre
    offset = np.where(stance_right[:, None], offsets["right"], offsets["left"])
    centre_z = lateral_displacement(attrs, pieces.windows, samples.t)
    dz = centre_z + offset[:, 2] - np.where(stance_right, foot_z["right"], foot_z["left"])
    hip_height = np.sqrt(hip_sim[:, 1] ** 2 - dz ** 2)
    centre = np.column_stack([hip_sim[:, 0] - offset[:, 0], hip_height - offset[:, 1], centre_z])
    # the hips are the centre plus the same offsets (hip_positions from the centre: the same sums)
    return LegPlanes(foot_z, {side: centre + offsets[side] for _, side in SIDES}), centre, lean, hip_sim


def ground_legs(walk, samples: Samples, hips: dict, toe_off_hips: np.ndarray | None = None):
    """The legs while their feet are on the ground: the virtual leg (§4.2) of each stance, from its
    heel strike through the next step's double support to toe-off, evaluated on its own stance
    times (so that its foot stays planted) with its hips ``hips[side]`` (n, 2) in its plane.

    Returns (side -> point name -> (n, 2), filled on the rows it covers; side -> those rows (bool)),
    and with ``toe_off_hips`` (steps, 2), each step's hind leg's own hip at its toe-off, also
    :func:`toe_off_feet` of them, evaluated in the same pass (each call of the virtual legs costs
    mostly its fixed overhead)."""
    n = len(samples.t)
    t_ds = np.array([s.plan.timings.t_ds for s in walk.steps])
    in_double_support = samples.tau <= t_ds[samples.step]
    # each stance foot with the step it lands in (step 0's hind foot stood before the walk began)
    feet = [(-1, walk.steps[0].hind_foot)] + [(k, walk.stance_foot(k)) for k in range(len(walk.steps))]
    sides, rows, t_leg = [], [], []
    for k, foot in feet:
        sides.append(stance_leg(k) if k >= 0 else _OTHER[stance_leg(0)])
        own = np.flatnonzero(samples.step == k)
        later = np.flatnonzero((samples.step == k + 1) & in_double_support)
        rows.append(np.r_[own, later])
        t_leg.append(np.r_[_stance_times(foot, samples.tau[own]), foot.t_step + samples.tau[later]])
    which = np.repeat(np.arange(len(feet)), [len(r) for r in rows])
    t_leg, leg_hips = np.concatenate(t_leg), np.vstack([hips[side][r] for side, r in zip(sides, rows)])
    if toe_off_hips is not None:
        # step j's hind foot is feet[j] (step 0's stood before the walk, step j's is step j - 1's stance)
        which = np.r_[which, np.arange(len(walk.steps))]
        t_leg = np.r_[t_leg, [s.hind_foot.t_toe_off for s in walk.steps]]
        leg_hips = np.vstack([leg_hips, toe_off_hips])
    legs = stance_frames([foot for _, foot in feet], which, t_leg, leg_hips)
    pull = _overreach_pull(legs)
    # the knee of a leg whose foot hangs from it: the inverse kinematics of the foot's ankle
    knee = np.where(legs.overreach[:, None] > 0, leg_ik(walk.spec.body, legs.hip, legs.ankle + pull)[2], legs.knee)
    points = {side: {name: np.full((n, 2), np.nan) for name in _POINTS} for _, side in SIDES}
    covered = {side: np.zeros(n, bool) for _, side in SIDES}
    start = 0
    for (k, _), side, r in zip(feet, sides, rows):
        mine = slice(start, start + len(r))
        for name in _POINTS:
            points[side][name][r] = (knee if name == "knee" else getattr(legs, name))[mine] + (pull[mine] if name in _FOOT else 0.0)
        covered[side][r] = True
        start += len(r)
    if toe_off_hips is None:
        return points, covered
    return points, covered, ((legs.ankle + pull)[start:], legs.pitch[start:])


def _overreach_pull(legs) -> np.ndarray:
    """(n, 2): where the hip is beyond the leg's reach of its foot (long steps, late in the double
    support), the straight leg ends short of the foot's ankle: the foot hangs from it, its toe off
    the ground a little early, rather than a shank stretched to the planted foot (the skeleton's
    segments are rigid) and a leg that jumps to the swing's posture at toe-off. The foot's points
    move by this."""
    toward_hip = legs.hip - legs.ankle
    return toward_hip * (legs.overreach / np.maximum(np.hypot(*toward_hip.T), 1e-12))[:, None]


def toe_off_feet(walk, hips_at) -> tuple[np.ndarray, np.ndarray]:
    """Each step's hind leg at its toe-off as the body shows it, its virtual leg on the leg's own
    hip in its plane (the swing leg of the step starts from it): the ankle (steps, 2) and the
    foot's pitch (steps,)."""
    feet = [s.hind_foot for s in walk.steps]
    every = np.arange(len(feet))
    _, own = hips_at(every, np.array([s.plan.timings.t_ds for s in walk.steps]))
    legs = stance_frames(feet, every, np.array([f.t_toe_off for f in feet]), own)
    return legs.ankle + _overreach_pull(legs), legs.pitch


def pelvis_angles_at(walk, t: np.ndarray) -> np.ndarray:
    """The pelvis's tilt, list and rotation (n, 3) (rad, docs/skeleton.md's signs: list + right hip
    up, rotation + right hip forward) at walk times ``t``: each step's schedule, whose rotation
    puts the stance side's hip forward and whose list lowers the swing side."""
    t = np.asarray(t, float)
    step, tau = locate_steps(walk.steps, t)
    out = np.zeros((len(t), 3))
    if len(t):
        rotation, lowered = PelvisSchedule.per_sample([s.pelvis for s in walk.steps], step).angles(tau)
        sign = np.where([stance_leg(k) == "right" for k in range(len(walk.steps))], 1.0, -1.0)[step]
        out[:, 1], out[:, 2] = sign * lowered, sign * rotation
    return out


def swing_hips(walk, pelvis_at, pieces: WalkPieces | None = None):
    """``hips_at(step, tau)`` for :func:`.swing_legs.swing_legs`: the simulated hip and the swinging
    leg's own hip in its plane, (n, 2) each, at samples of steps ``step`` and times ``tau``, with
    the pelvis angles ``pelvis_at(t)`` (n, 3) at walk times t."""
    pieces = WalkPieces.of(walk) if pieces is None else pieces

    def hips_at(step, tau):
        samples = Samples(pieces.starts[step] + tau, step, tau)
        planes, _, _, simulated = leg_planes(walk, samples, pelvis_at(samples.t), pieces)
        swinging_left = pieces.stance_right[step][:, None]
        own = np.where(swinging_left, planes.hip_in_plane("left"), planes.hip_in_plane("right"))
        return model_swing_hips(walk, step, tau, simulated), own
    return hips_at


def model_swing_hips(walk, step: np.ndarray, tau: np.ndarray, simulated: np.ndarray) -> np.ndarray:
    """The planar model's swing hip (n, 2) at samples of steps ``step`` and times ``tau``: the
    simulated (stance) hip ``simulated`` plus the step's pelvis offset to its other hip, the hip
    the swing was solved from."""
    if not len(simulated):
        return np.array(simulated, float)
    return PelvisSchedule.per_sample([s.pelvis for s in walk.steps], step).swing_side_hips(tau, simulated)


def _stance_times(foot, tau: np.ndarray) -> np.ndarray:
    """The stance foot's own times at its step's ``tau``. The walk's last stance leg has no double
    support to complete its rules, and the walk ends at the instant it would begin: that last
    instant keeps the single support's pitch."""
    return tau if foot.complete else np.minimum(tau, np.nextafter(foot.t_step, 0.0))


def body_motion(walk, fps: float) -> BodyMotion:
    """The body at every frame t = k/fps, k = 0 .. floor(duration·fps), of a walk with at least one
    step (:class:`~klaw_ocp.walk.Walk`)."""
    if not walk.steps:
        raise ValueError("walk: no completed step, so no body motion")
    return body_motion_at(walk, Samples.of(walk, fps))


def body_motion_at(walk, samples: Samples) -> BodyMotion:
    """The body at the frames ``samples`` (walk times within the walk's steps). Every frame reads
    only its own step and its neighbours (the stance leg's toe-off in the next step's double
    support, the hind leg's stance in the previous one), so a walk of a few steps around a step
    gives that step's frames as the whole walk does (:func:`step_frames`)."""
    body, attrs = walk.spec.body, walk.spec.attributes
    pelvis_at = lambda t: pelvis_angles_at(walk, t)
    pieces = WalkPieces.of(walk)
    # the frames and every step's toe-off (toe_off_feet's samples, as swing_hips makes them) in
    # one pass of the pelvis, the planes and the virtual legs: each pass costs mostly its fixed
    # overhead of some hundred small numpy calls, not its samples
    n, every = len(samples.t), np.arange(len(walk.steps))
    t_ds = np.array([s.plan.timings.t_ds for s in walk.steps])
    both = Samples(np.r_[samples.t, pieces.starts + t_ds], np.r_[samples.step, every], np.r_[samples.tau, t_ds])
    pelvis_both = pelvis_at(both.t)
    planes, centre, lean, simulated = leg_planes(walk, both, pelvis_both, pieces)
    both_hips = {side: planes.hip_in_plane(side) for _, side in SIDES}
    toe_off_hips = np.where(pieces.stance_right[:, None], both_hips["left"][n:], both_hips["right"][n:])
    planes = LegPlanes(planes.foot_z, {side: hip[:n] for side, hip in planes.hips.items()})
    pelvis_angles, centre, lean, simulated = pelvis_both[:n], centre[:n], lean[:n], simulated[:n]
    hips = {side: hip[:n] for side, hip in both_hips.items()}
    in_plane, on_ground, toe_off = ground_legs(walk, samples, hips, toe_off_hips)
    # at any instant at most one leg swings: both legs' swings in one pass
    swinging = {side: np.flatnonzero(~on_ground[side]) for _, side in SIDES}
    rows = np.concatenate(list(swinging.values()))
    hips_at = swing_hips(walk, pelvis_at, pieces)
    own = np.vstack([hips[side][r] for side, r in swinging.items()])     # (the frames' planes, once)
    model_hips = model_swing_hips(walk, samples.step[rows], samples.tau[rows], simulated[rows])
    swung = swing_legs(walk, samples.step[rows], samples.tau[rows], hips_at, toe_off, hips=(model_hips, own))
    start, legs = 0, {}
    for side, r in swinging.items():
        for name in _POINTS:
            in_plane[side][name][r] = swung[name][start:start + len(r)]
        start += len(r)
        legs[side] = LegPoints(**planes.all_to_world(side, in_plane[side]))
    t, root, pelvis = samples.t, centre, pelvis_angles
    angles = skeleton_angles(body, root, pelvis, legs, UpperBody.neutral())
    hip_flexion = {side: angles[:, column] for side, column in _HIP_FLEXION.items()}
    upper = upper_body_motion(attrs, t, lean, hip_flexion, pelvis, arm_swing_at(walk, samples))
    for name, values in upper_body_angles(upper, len(t)).items():
        angles[:, ANGLE_NAMES.index(name)] = values
    return BodyMotion(t, root, pelvis, legs, upper, angles)
