"""What a step is given and what it gives (:mod:`.step`): :class:`StepInput` (where it starts and how
the body arrives there), :class:`StanceStage` (its stance half, solved first) and
:class:`StepResult` (the whole step solved)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from .. import choices
from ..gait import StepPlan
from ..kinematics.pelvis import PelvisSchedule
from ..kinematics.swing_foot import SwingFoot
from ..kinematics.virtual_leg import StanceFoot
from ..solvers import SubphaseSolution
from ..solvers.plain_shooting import EVENT_FREE_ROOT
from .stance_spec import lock_rule_nodes


@dataclass
class StepInput:
    """What a step needs besides its plan: where it starts and how the body arrives there."""
    x0: np.ndarray                 # stance state at heel strike, relative to the stance ankle
    origin_x: float                # stance ankle x (flat-foot ankle, eq. 3's ankle1)
    hind_ankle_x: float            # flat-foot ankle x of the hind (soon swinging) leg
    y_start: float                 # hip height above the stance ankle at heel strike
    excursion: float               # height of the hip's mid-step bump (0 for start/stop steps)
    #: the hind leg's virtual leg: its stance so far (the previous step's ``stance_foot``)
    hind_foot: StanceFoot | None = None
    #: the stance foot stands flat from the start, with no heel strike (a walk from rest's first step)
    stance_standing: bool = False
    #: the next step's double support (s), which ends with this stance leg's toe-off; None: the
    #: walk's last step (its own double support stands in)
    next_t_ds: float | None = None
    #: the pelvis's rotation at this heel strike (rad): the one the step before ended with (its
    #: plan's ``pelvic_rotation``, which eq. 3 split it by); None: this step's own (0 standing)
    pelvis_rotation: float | None = None


@dataclass(frozen=True)
class StepResult:
    """A solved step, built once when it is solved: its subphase solutions, the kinematic double
    support of the hind leg and the virtual-leg rules of its own stance leg. The stance leg's
    double support, and so its toe-off, belongs to the next step (its ``hind_foot``):
    :meth:`klaw_ocp.walk.Walk.stance_foot` gives the leg completed."""
    index: int
    origin_x: float
    hind_ankle_x: float
    t_start: float
    subphases: list[SubphaseSolution]
    #: the hind leg's samples over the double support (``t``, ``theta3``, ``theta4``, ``pitch``)
    double_support: dict
    #: curve P's numbers (:meth:`klaw_ocp.control.step_stages.CurveP.as_dict`)
    curve_p: dict
    final_stance_state: np.ndarray
    heel_clearance_min: float
    plan: StepPlan
    notes: list[str]
    #: the hip-height sinusoid the stance is guided towards (§4.2), in the stance ankle's frame:
    #: ``y_start``/``y_end`` (the two heel-strike heights) and ``excursion`` (the mid-step bump), m,
    #: and the bump's ``rise`` and ``fall`` (fractions of the step) and the fall's ``power``
    hip_reference: dict
    #: the hind leg's virtual leg, completed by this step's double support (the previous stance
    #: leg's rules with their toe-off), and its samples there: (leg stance times, world hips (n, 2))
    hind_foot: StanceFoot
    hind_samples: tuple[np.ndarray, np.ndarray]
    #: this step's stance leg: the rules its own stance fixed (heel strike, foot flat, heel-off;
    #: :func:`klaw_ocp.control.step_stages.stance_leg_rules`); the next step's double support
    #: completes them into that step's ``hind_foot``
    stance_foot: StanceFoot
    #: the world hip at every stance node (m)
    stance_hips: np.ndarray
    #: the swing foot's angle schedule, step-local times
    swing_foot: SwingFoot
    #: the pelvis's rotation and list about the stance hip (§4.2), which carry the swing leg's hip
    pelvis: PelvisSchedule
    #: how far ahead of its heel-strike angle the thigh peaked at t1 (deg): the attribute
    #: ``terminal_swing_retraction``, or more where the swing leg needed it to clear the ground
    #: (control/swing_clearance.py); a closing step's is negative (behind: step_stages.thigh_peak)
    thigh_retraction_deg: float = 0.0
    #: a solved step has its swings; a :class:`StanceStage` (the stance half) has not
    has_swings: ClassVar[bool] = True

    def subphase(self, name: str) -> SubphaseSolution:
        return next(s for s in self.subphases if s.name == name)


@dataclass(frozen=True)
class StanceStage:
    """The first half of a step (:meth:`StepController.solve_stance_stage`): the stance solved, the
    stance leg's heel-strike foot, the pelvis and the hind leg's rules completed by the double
    support; :meth:`StepController.solve_swing_stage` finds the stance leg's heel-off, the hind
    leg's postures over the double support and the swings from it, into the :class:`StepResult`.

    The body's frames of the step before read only this half: its swing leg lands on this stance
    foot, and its stance leg is completed by this double support. So the live playground sends a
    step's frames once the next step's stance half is solved and solves the rest of that step after
    sending (docs/serve.md). It reads as a :class:`StepResult` where the body reads one, without
    its swings."""
    index: int
    plan: StepPlan
    inp: StepInput
    at_rest: bool
    stance: SubphaseSolution
    stance_ctx: dict
    #: the world stance hip at every stance node, and its velocity (m, m/s)
    stance_hips: np.ndarray
    hip_vels: np.ndarray
    #: the swing leg's own hip (the pelvis's other one) at every stance node, and its velocity
    other_hips: np.ndarray
    other_vels: np.ndarray
    #: the stance leg's rules as its heel strike fixed them (its heel-off is found with the swings)
    landing_foot: StanceFoot
    pelvis: PelvisSchedule
    #: the hind leg's rules completed by this step's double support, to toe-off
    hind_foot: StanceFoot
    has_swings: ClassVar[bool] = False

    @property
    def t_start(self) -> float:
        return self.plan.t_start

    @property
    def origin_x(self) -> float:
        return self.inp.origin_x

    @property
    def stance_foot(self) -> StanceFoot:
        """What the step before reads of this stance leg: the foot its swing leg lands on
        (``landing_foot``)."""
        return self.landing_foot

    @property
    def subphases(self) -> list:
        return [self.stance]

    def subphase(self, name: str) -> SubphaseSolution:
        if name != "stance":
            raise ValueError(f"step {self.index}: its {name} is not solved yet (a stance stage)")
        return self.stance

def solved_without_events(stance: SubphaseSolution) -> bool:
    """Whether plain shooting took a stance's root with its lock events disarmed (the smooth
    problem's, keeping the lock rule at the nodes: solvers/plain_shooting.py, EVENT_FREE_ROOT); the
    swings that re-simulate it then disarm them too, as a closing stance's do."""
    return EVENT_FREE_ROOT in stance.fallbacks


def lock_rule_notes(stance: SubphaseSolution, l1: float, tol: float = 1e-7) -> list:
    """How the stance met the lock rule (w <= l1 while theta1 < 0, once the leg has come down to l1).

    Plain shooting locks the leg (events); multiple shooting holds the rule as a path constraint,
    re-solving with IPOPT when the square solution breaks it. A breach left in a solution (the
    closing stance, or ``nlp: rootfinder``) is reported, not hidden.
    """
    if stance.events:
        return [f"stance lock events: {', '.join(f'{n} at t={t:.3f} s' for n, t in stance.events)}"]
    w = stance.states[:, 0]
    on_limit = lock_rule_nodes(stance.states, l1) & (w > l1 - tol)
    breach = np.flatnonzero(on_limit & (w > l1 + tol))
    if breach.size:
        return [f"lock rule not enforced: w exceeds l1 by {w[breach].max() - l1:.3g} m at "
                f"t={stance.t[breach[0]]:.3f} s while theta1 < 0"]
    if on_limit[1:].any() and stance.nlp == choices.IPOPT:
        return [f"lock rule held by the path constraint w <= l1 (IPOPT), first at t={stance.t[np.argmax(on_limit)]:.3f} s"]
    return []
