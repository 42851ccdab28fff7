"""Step symmetry: section 3, eq. 3, the final conditions of a step at heel strike.

Frame: x forward, y up, ground at y = 0. The stance leg's origin ``ankle1`` is the flat-foot
ankle of the stance foot, at (x_a, y_a) = (x_a, l9) (ERRATA 6: the printed "l0" is l9, the
ankle height; l0 is the pelvis width). The swing leg lands straight, its kinematic foot touching
the ground with the heel at::

    heel = (x_nh, 0) = (x_a + sl - l8, 0)             (ERRATA 6: the printed "l_g" is l8)

The triangle hip-ankle-heel of the landing leg has sides l1 (hip-ankle), l11 (ankle-heel) and r
(hip-heel), and its interior angle at the ankle is θ5 + ω8, where cos ω8 = l8/l11 and θ5, the
ankle angle at impact, is a locomotion attribute. We read θ5 literally (ERRATA, open choice): the
angle between the leg axis and the foot's long axis, about 90° for a neutral ankle; the other
reading gives w < l1 at heel strike, against the text's w > l1. The cosine law gives::

    r² = l1² + l11² - 2·l1·l11·cos(θ5 + ω8)
    ω3 = acos((l1² + r² - l11²) / (2·l1·r))           (angle at the hip between leg and heel)
    hip = (x_h, y_h) = (x_a + sl/2, sqrt(r² - (x_nh - x_h)²))
    w  = sqrt((y_h - y_a)² + (sl/2)²)                  (stance leg length)
    θ1 = asin(sl / (2w))                              (stance leg, > 0: hip ahead of the ankle)
    θ3 = -ω3 - asin((x_nh - x_h) / r)                 (swing thigh, < 0: foot ahead of the hip)

The hip's place along the step (our deviation, attribute ``heel_strike_hip_lead``, which
:func:`klaw_ocp.gait.plan.heel_strike_hip_lead` scales for slow steps): eq. 3 puts
the hip half-way, x_h = x_a + sl/2, both legs spanning the same distance. People's hip at heel
strike is nearer the leading foot: the trailing foot already stands on its ball, which reaches
further back, while the leading leg lands nearly straight. We put the hip ``lead`` = f·sl ahead of
half-way. The landing leg then spans less of the step, so the hip is higher, and the trailing leg
more; its foot, on its ball, pitches as a person's does (docs/human-gait.md, "The hip ahead of
mid-step"). f = 0 is the paper's eq. 3. The stance leg at heel strike is then no longer the mirror
of the next stance's start: ``landing_w`` and ``landing_theta1`` give the latter::

    x_h = x_a + (sl - hip_shift)/2 + lead,   w = sqrt((y_h - y_a)² + (x_h - x_a)²)

With a pelvis (§4.2, the determinants; :mod:`klaw_ocp.kinematics.pelvis`) the landing leg hangs
from the pelvis's other hip, ``hip_shift`` = l0 sin ψ ahead of the stance hip at heel strike
(pelvic rotation ψ, list 0 there). The symmetric step then gives each leg (sl - hip_shift)/2 of
the step: the stance hip is at x_a + (sl - hip_shift)/2 and the landing hip, from which θ3 is
measured, hip_shift ahead of it, at the same height. Pelvic rotation so lengthens the step
without lowering the hip (Saunders' first determinant of gait); hip_shift = 0 is the paper's
one-hip step.

Signs follow the errata's conventions (stance hip = ankle + w·(sin θ1, cos θ1); swing ankle =
hip - l1·(sin θ3, cos θ3) for a straight leg). For a compass gait without feet θ3 = -θ1 (ERRATA
6); the foot makes |θ3| < θ1.

Stance origin (ERRATA, open choice): the next stance leg's origin is its own flat-foot ankle at
``next_ankle_x = x_a + sl``, i.e. the heel at heel strike plus l8. With it (and no hip lead) the
next stance starts at the mirror image of the end of the previous one, and consecutive origins are
exactly one step length apart.
"""
from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ..body import Body
from ..errors import ConfigError, GaitLimitError, finite_real, out_of_range
from .attributes import LocomotionAttributes, resolve


@dataclass(frozen=True)
class StepConstraints:
    """The final conditions of a step at heel strike (eq. 3) and the geometry behind them.

    Lengths in m, angles in rad, positions in the world frame (x forward, y up, ground y = 0).

    Attributes:
        step_length: sl, m.
        w: stance leg length at heel strike (> l1: the foot lifts the hip).
        theta1: stance leg angle from the vertical, > 0 with the hip ahead of the ankle.
        theta3: swing thigh angle from the vertical, < 0 with the foot ahead of the hip.
        r: distance hip to the landing heel.
        omega3: angle at the hip between the landing leg axis and the hip-heel line.
        hip_x, hip_y: hip position at heel strike.
        ankle_x, ankle_y: stance origin ``ankle1`` (flat-foot ankle, y = l9).
        heel_x: x of the landing heel (on the ground).
        next_ankle_x: the next stance origin, x_a + sl (flat-foot ankle of the new stance leg).
        theta5: ankle angle at impact used, rad.
        hip_shift: how far the landing leg's hip (the pelvis's other hip) is ahead of the stance
            hip at heel strike, m (0: the one-hip model).
        hip_lead: how far the stance hip is ahead of half-way along the step, m (0: eq. 3's
            symmetric step; ``heel_strike_hip_lead`` times sl).
    """

    step_length: float
    w: float
    theta1: float
    theta3: float
    r: float
    omega3: float
    hip_x: float
    hip_y: float
    ankle_x: float
    ankle_y: float
    heel_x: float
    next_ankle_x: float
    theta5: float
    hip_shift: float = 0.0
    hip_lead: float = 0.0

    @property
    def closing(self) -> bool:
        """Whether this is the step that ends a walk at rest (``step_constraints(closing=True)``):
        the swing foot lands beside the stance foot, sl = 0."""
        return self.step_length == 0

    @property
    def landing_w(self) -> float:
        """The next stance leg's length at this heel strike: the landing hip to the next origin."""
        return math.hypot(self.hip_y - self.ankle_y, self.landing_hip_x - self.next_ankle_x)

    @property
    def landing_theta1(self) -> float:
        """The next stance leg's angle at this heel strike (< 0: the hip behind its ankle)."""
        return math.asin((self.landing_hip_x - self.next_ankle_x) / self.landing_w)

    @property
    def landing_hip_x(self) -> float:
        """x of the hip the landing leg hangs from at heel strike."""
        return self.hip_x + self.hip_shift

    def as_dict(self) -> dict[str, float]:
        return asdict(self)


def _finite(field: str, value, allowed: str, positive: bool) -> float:
    number = finite_real(value)
    if number is None or (positive and number <= 0):
        raise ConfigError(out_of_range(field, value, allowed))
    return number


def step_constraints(body: Body, step_length, attributes: LocomotionAttributes | None = None,
                     ankle_x=0.0, closing: bool = False, hip_shift: float = 0.0,
                     hip_lead: float = 0.0) -> StepConstraints:
    """The heel-strike final conditions (w, θ1, θ3) of a step of length ``step_length`` (eq. 3,
    with the hip ``hip_lead`` of the step ahead of half-way).

    Args:
        body: anthropometry (l1, l8, l9, l11, ω8).
        step_length: sl in m, ankle to ankle.
        attributes: gives ``theta5_impact`` (deg).
        ankle_x: x of the stance origin ankle1 (the previous step's ``next_ankle_x``).
        hip_shift: the landing leg's hip ahead of the stance hip at heel strike (m, the pelvis's
            rotation; 0 in a closing step, whose feet end side by side).
        hip_lead: how far the hip is ahead of half-way along the step, as a fraction of it (0: the
            paper's eq. 3; :func:`klaw_ocp.gait.plan.heel_strike_hip_lead` gives a step's; 0 in a
            closing step).

    Raises:
        ConfigError: sl is not a finite number > 0, or ankle_x is not finite.
        GaitLimitError: the landing leg cannot reach the ground at that step length.
    """
    # closing=True: the last step of a walk that ends at rest, which lands the swing foot beside
    # the stance foot (sl = 0: theta1 = 0 and w = l1 at theta5_impact = 90 deg)
    sl = _finite("walk.step_length", step_length, "a finite number > 0 in m", positive=not closing)
    if sl < 0:
        raise ConfigError(out_of_range("walk.step_length", sl, "a finite number >= 0 in m"))
    x_a = _finite("ankle_x", ankle_x, "a finite number in m", positive=False)
    attrs = resolve(attributes)
    th5 = attrs.rad("theta5_impact")
    l1, l8, l9, l11 = body.l1, body.l8, body.l9, body.l11
    y_a = l9

    r2 = l1 ** 2 + l11 ** 2 - 2.0 * l1 * l11 * math.cos(th5 + body.omega8)
    r = math.sqrt(r2)  # > 0: l1 > l11 for any body, so the triangle never degenerates
    # Clamp the rounding of a nearly degenerate triangle; the argument is in [-1, 1] analytically.
    omega3 = math.acos(max(-1.0, min(1.0, (l1 ** 2 + r2 - l11 ** 2) / (2.0 * l1 * r))))

    shift = 0.0 if closing else float(hip_shift)
    # a closing step lands the feet side by side (sl = 0), where no hip lead is defined
    lead_fraction = 0.0 if closing else _finite("hip_lead", hip_lead, "a finite number below 0.5", positive=False)
    if lead_fraction >= 0.5:
        raise ConfigError(out_of_range("hip_lead", lead_fraction, "a finite number below 0.5"))
    lead = lead_fraction * sl
    half = 0.5 * (sl - shift)           # each leg's share of a symmetric step (the pelvis spans the rest)
    x_nh = x_a + sl - l8
    x_h = x_a + half + lead
    dx = x_nh - (x_h + shift)
    dy2 = r2 - dx ** 2
    # the hip would drop to ankle height: dx = sqrt(r² - y_a²), solved for sl
    sl_max = (math.sqrt(max(0.0, r2 - y_a ** 2)) + l8 + 0.5 * shift) / (0.5 - lead_fraction)
    if dy2 <= 0.0 or math.sqrt(dy2) <= y_a:
        raise GaitLimitError(f"walk.step_length: got {sl:.6g} m, allowed below {sl_max:.4g} m "
                             f"(eq. 3: the landing leg cannot reach the ground with the hip above "
                             f"the stance ankle at theta5_impact = {attrs.theta5_impact:g} deg)")
    y_h = math.sqrt(dy2)
    w = math.hypot(y_h - y_a, half + lead)
    theta1 = math.asin((half + lead) / w)
    theta3 = -omega3 - math.asin(dx / r)
    return StepConstraints(step_length=sl, w=w, theta1=theta1, theta3=theta3, r=r, omega3=omega3,
                           hip_x=x_h, hip_y=y_h, ankle_x=x_a, ankle_y=y_a, heel_x=x_nh,
                           next_ankle_x=x_a + sl, theta5=th5, hip_shift=shift,
                           hip_lead=lead)


def landing_heel(body: Body, c: StepConstraints) -> tuple[float, float]:
    """Rebuild the landing heel from the hip, θ3 and the foot (the inverse of eq. 3).

    The straight swing leg puts the ankle at hip - l1·(sin θ3, cos θ3); the heel is l11 from the
    ankle along the ankle→hip direction rotated counter-clockwise by θ5 + ω8. Used by tests and
    by the swing phase to check that eq. 3 closes.
    """
    ax = c.landing_hip_x - body.l1 * math.sin(c.theta3)
    ay = c.hip_y - body.l1 * math.cos(c.theta3)
    ux, uy = math.sin(c.theta3), math.cos(c.theta3)  # unit vector ankle -> hip
    a = c.theta5 + body.omega8
    return (ax + body.l11 * (ux * math.cos(a) - uy * math.sin(a)),
            ay + body.l11 * (ux * math.sin(a) + uy * math.cos(a)))
