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
from ..kernels import prefetch
from ..kinematics.pelvis import PelvisSchedule
from . import leg_angles, stance_kernel, swing_kernel
from .pose import LegPoints, UpperBody, hip_positions, pelvis_rotations, set_upper_body_angles, skeleton_angles
from .skeleton import ANGLE_NAMES, SIDES
from .stance_legs import POINTS, OpenStance, ground_legs, open_points
from .swing_legs import landing_pose, swing_legs, swing_samples
from .upper_body import StepWindow, lateral_displacement, step_amplitudes, upper_body_motion
from .walk_samples import frame_times, locate_steps, stance_at, stance_curves

#: The columns of angles.csv: time (s), the root (pelvis centre, m), then the 56 angles (degrees).
ANGLES_COLUMNS = ("time", "root_x", "root_y", "root_z") + ANGLE_NAMES
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

    def stacked_to_world(self, side: str, p: np.ndarray) -> np.ndarray:
        """In-plane points of the leg stacked (k, n, 2), at every sample -> world points (k, n, 3)."""
        hip, z_foot = self.hips[side], self.foot_z[side]
        dz = hip[:, 2] - z_foot
        v_leg = np.hypot(hip[:, 1], dz)
        v = p[..., 1]
        return np.stack([p[..., 0], v * hip[:, 1] / v_leg, z_foot + v * dz / v_leg], axis=-1)


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


def leg_planes(walk, samples: Samples, pelvis_angles: np.ndarray, pieces: WalkPieces | None = None,
               rotation: np.ndarray | None = None) -> tuple[LegPlanes, np.ndarray, np.ndarray, np.ndarray]:
    """The pelvis and the legs' planes at the samples: (planes, pelvis centre (n, 3), lean θ2 (n,),
    the simulated hip (n, 2): x and height in the planar model).

    The simulated hip is the current step's stance hip, exact in its leg's plane: its in-plane
    height is the simulated height v, so its world height is sqrt(v² − dz²). The pelvis centre
    is then where the pelvis angles put it from that hip, at the lateral displacement's z; the
    other hip is where the pelvis puts it (:func:`.pose.hip_positions`). ``rotation``: the pelvis's
    rotations (:func:`.pose.pelvis_rotations`) when the caller has them."""
    body, attrs = walk.spec.body, walk.spec.attributes
    pieces = WalkPieces.of(walk) if pieces is None else pieces
    n = len(samples.t)
    hip_sim, lean = stance_at(walk, pieces.stance, samples.step, samples.tau)
    half = attrs.foot_lateral_distance / 2    # the distance between the feet's centrelines
    foot_z = {"right": half, "left": -half}
    stance_right = pieces.stance_right[samples.step]
    offsets = hip_positions(body, np.zeros((n, 3)), pelvis_angles, rotation)     # each hip from the pelvis centre
    offset = np.where(stance_right[:, None], offsets["right"], offsets["left"])
    centre_z = lateral_displacement(attrs, pieces.windows, samples.t)
    dz = centre_z + offset[:, 2] - np.where(stance_right, foot_z["right"], foot_z["left"])
    hip_height = np.sqrt(hip_sim[:, 1] ** 2 - dz ** 2)
    centre = np.column_stack([hip_sim[:, 0] - offset[:, 0], hip_height - offset[:, 1], centre_z])
    # the hips are the centre plus the same offsets (hip_positions from the centre: the same sums)
    return LegPlanes(foot_z, {side: centre + offsets[side] for _, side in SIDES}), centre, lean, hip_sim


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


def prepare_kernels() -> None:
    """Compile (the first time on a machine, in parallel) or load the body's compiled kernels now,
    rather than at the first frames: a command that solves does it inside its compile notice."""
    libraries = (leg_angles.library(), stance_kernel.library(), *swing_kernel.libraries())
    if any(library.will_compile() for library in libraries):
        prefetch([library.load for library in libraries])
    for library in libraries:
        library.load()          # (loaded once a process: later calls return at once)


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
    gives that step's frames as the whole walk does (:func:`klaw_ocp.step_body.step_frames`)."""
    return finish_body(walk, prepare_body(walk, samples))


@dataclass(frozen=True)
class PreparedBody:
    """The body at frames before its legs' angles and the upper body (:func:`prepare_body`)."""
    samples: Samples
    centre: np.ndarray           # (n, 3) the pelvis centre (the root)
    pelvis_angles: np.ndarray    # (n, 3)
    rotation: np.ndarray         # the pelvis's rotations (:func:`.pose.pelvis_rotations`)
    lean: np.ndarray             # (n,) θ2
    planes: LegPlanes            # at the frames
    points: np.ndarray           # (side, point, frame, 2) each leg in its plane (SIDES, POINTS order)
    opened: OpenStance | None    # frames whose stance foot the window's next step completes
    landing: tuple | None        # what the last step's swing read of the foot it lands on (swing_legs.landing_pose)


def prepare_body(walk, samples: Samples, landing=None) -> PreparedBody:
    """The body at the frames ``samples`` as far as the walk fixes it: the pelvis, the legs' planes,
    the stance legs and the swing leg in their planes. ``landing``: where the walk is a window
    whose next step is planned but not solved (the live playground builds a step's body while the
    page shows the step before), the foot the last step's swing leg lands on
    (:meth:`klaw_ocp.step_loop.StepLoop.next_landing`); the frames on the last stance foot are then
    left open, for the next step's double support completes that foot's rules
    (:func:`finish_body` with the window that has the next step's stance half)."""
    pieces = WalkPieces.of(walk)
    n, m = len(samples.t), len(walk.steps)
    t_ds = np.array([s.plan.timings.t_ds for s in walk.steps])
    # the steps whose swing leg the frames show: at any instant at most one leg swings, the stance
    # leg's other one once the double support is over (where ground_legs leaves it)
    swing_steps = np.unique(samples.step[~(samples.tau <= t_ds[samples.step])])
    at_step, at_tau, grids = swing_samples(walk, swing_steps, landing)
    # the frames, every step's toe-off (toe_off_feet's samples) and the swing legs' own samples (as
    # swing_hips makes them) in one pass of the pelvis, the planes and the virtual legs: each pass
    # costs mostly its fixed overhead of some hundred small numpy calls, not its samples
    every = np.arange(m)
    both = Samples(np.concatenate([samples.t, pieces.starts + t_ds, pieces.starts[at_step] + at_tau]),
                   np.concatenate([samples.step, every, at_step]), np.concatenate([samples.tau, t_ds, at_tau]))
    pelvis_both = pelvis_angles_at(walk, both.t)
    rotation = pelvis_rotations(pelvis_both)          # (for the planes, and the frames' angles)
    planes, centre, lean, simulated = leg_planes(walk, both, pelvis_both, pieces, rotation)
    both_hips = {side: planes.hip_in_plane(side) for _, side in SIDES}
    # each leg's own hip where it swings (the stance leg's other one)
    own_both = np.where(pieces.stance_right[both.step][:, None], both_hips["left"], both_hips["right"])
    toe_off_hips, at_own = own_both[n:n + m], own_both[n + m:]
    planes = LegPlanes(planes.foot_z, {side: hip[:n] for side, hip in planes.hips.items()})
    at_simulated, simulated = simulated[n + m:], simulated[:n]
    hips = {side: hip[:n] for side, hip in both_hips.items()}
    points, on_ground, toe_off, opened = ground_legs(walk, samples, hips, toe_off_hips, open_last=landing is not None)
    swinging = [np.flatnonzero(~on_ground[i]) for i in range(len(SIDES))]
    rows = np.concatenate(swinging)
    own = np.vstack([hips[side][r] for (_, side), r in zip(SIDES, swinging)])     # (the frames' planes, once)
    # the model's swing hips at the swinging frames and at the swing legs' samples, in one pass
    k = len(rows)
    model_hips = model_swing_hips(walk, np.concatenate([samples.step[rows], at_step]),
                                  np.concatenate([samples.tau[rows], at_tau]),
                                  np.concatenate([simulated[rows], at_simulated]))
    hips_at = swing_hips(walk, lambda t: pelvis_angles_at(walk, t), pieces)   # (only if the swinging steps differ)
    swung = swing_legs(walk, samples.step[rows], samples.tau[rows], hips_at, toe_off, hips=(model_hips[:k], own),
                       sampled=(swing_steps, (at_step, at_tau, grids), (model_hips[k:], at_own)), landing=landing)
    swung, start = np.stack([swung[name] for name in POINTS]), 0
    for i, r in enumerate(swinging):
        points[i][:, r] = swung[:, start:start + len(r)]
        start += len(r)
    return PreparedBody(samples, centre[:n], pelvis_both[:n], rotation[:n], lean[:n], planes, points, opened,
                        None if landing is None else landing_pose(landing))


def finish_body(walk, prepared: PreparedBody) -> BodyMotion:
    """The body :func:`prepare_body` prepared, with its legs' angles and the upper body: ``walk``
    the one prepared, or its window with the next step's stance half after it where frames were
    left open (the upper body reads it too: the arm swing's amplitude moves to the next step's)."""
    body, samples, points = walk.spec.body, prepared.samples, prepared.points
    opened = prepared.opened
    if opened is not None:
        points = points.copy()
        points[opened.side, :, opened.rows] = open_points(body, walk.stance_foot(opened.step), opened)
    legs = {side: LegPoints(*prepared.planes.stacked_to_world(side, points[i])) for i, (_, side) in enumerate(SIDES)}
    t, root, pelvis = samples.t, prepared.centre, prepared.pelvis_angles
    angles = skeleton_angles(body, root, pelvis, legs, None, prepared.rotation)     # the upper body's angles below
    hip_flexion = {side: angles[:, column] for side, column in _HIP_FLEXION.items()}
    upper = upper_body_motion(walk.spec.attributes, t, prepared.lean, hip_flexion, pelvis, arm_swing_at(walk, samples))
    set_upper_body_angles(angles, upper)
    return BodyMotion(t, root, pelvis, legs, upper, angles)
