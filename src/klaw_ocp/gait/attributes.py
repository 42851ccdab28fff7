"""Locomotion attributes: the numbers that individualise a walk (section 3 and section 5).

The paper calls them *locomotion attributes* (up to 28 of them): the anatomical limits that eq. 1
is checked against (section 3, e.g. ``sf_max = 182 steps/min``), the ankle and metatarsal angles
at heel strike (section 4.3), the foot-period limits (section 4.2), the swing curve P (section
4.3), the spring and damping constants of the stance and swing controllers and the determinants
of gait (section 4.2). The paper gives few of their values; where it is silent the value is our
choice and the spec says so (see docs/paper-map.md and docs/attributes.md).

One registry, :data:`ATTRIBUTES`, holds every attribute's unit, default, allowed range and the
paper passage it comes from. :class:`LocomotionAttributes` is an immutable set of values checked
against that registry. Angles are stored in degrees, as users write them; :meth:`LocomotionAttributes.rad`
converts for the equations, which work in radians.
"""
from __future__ import annotations

import difflib
import math
import numbers
from collections.abc import Mapping
from dataclasses import dataclass
from types import MappingProxyType

from ..errors import ConfigError, finite_real, out_of_range

_OURS = "not in the paper; our choice, see docs/paper-map.md"


@dataclass(frozen=True)
class AttributeSpec:
    """One locomotion attribute: its unit, default and inclusive allowed range [low, high].

    ``paper`` quotes the passage the attribute comes from, or says that the value is our choice.
    Units: ``deg`` angles (converted with :meth:`LocomotionAttributes.rad`), ``l1`` a multiple of
    the leg length ``Body.l1``, ``l1/(km/h)`` a multiple of l1 per km/h, ``1`` a plain fraction.
    """

    name: str
    unit: str
    default: float
    low: float
    high: float
    paper: str
    group: str = ""

    def check(self, value, field: str | None = None) -> float:
        """Return ``value`` as a float, or raise ConfigError naming ``field`` (default
        ``attributes.<name>``)."""
        field = field or f"attributes.{self.name}"
        if isinstance(value, bool) or not isinstance(value, numbers.Real):
            raise ConfigError(out_of_range(field, value, f"a number in {self.unit}"))
        number = finite_real(value)
        if number is None or not self.low <= number <= self.high:
            raise ConfigError(out_of_range(field, value if number is None else number,
                                           f"{self.low:g} to {self.high:g} {self.unit}"))
        return number


def _spec(group, name, unit, default, low, high, paper):
    return AttributeSpec(name=name, unit=unit, default=default, low=low, high=high, paper=paper,
                         group=group)


_SPECS = [
    # -- limits that the completed locomotion parameters must respect (section 3, eq. 1)
    _spec("limits", "sf_max", "steps/min", 182.0, 60.0, 240.0,
          "§3: anatomical limit, 'e.g. sf_max = 182 steps/min'"),
    _spec("limits", "sf_min", "steps/min", 30.0, 1.0, 120.0, _OURS),
    _spec("limits", "speed_min", "km/h", 0.5, 0.01, 5.0,
          "§3 'within anatomical limits defined by locomotion attributes'; value " + _OURS),
    _spec("limits", "speed_max", "km/h", 9.0, 1.0, 15.0,
          "§3 'within anatomical limits'; value " + _OURS + " (walking turns to running near 9 km/h)"),
    _spec("limits", "step_length_max_rel", "l1", 1.4, 0.5, 2.5,
          "§3 'within anatomical limits'; maximum step length relative to leg length, " + _OURS),
    _spec("limits", "step_length_min_rel", "l1", 0.2, 0.01, 1.0, _OURS),
    _spec("limits", "max_speed_change_per_step", "km/h", 1.0, 0.05, 3.0,
          "§2.4 principle 1: parameters may change 'with a granularity of one step'; the largest change "
          "of a schedule from one step to the next that the solvers support, " + _OURS),
    _spec("limits", "start_speed_max", "km/h", 5.0, 0.5, 9.0,
          "§5, fig. 8: walks that start from standing (at 2 and 5 km/h); the fastest first step of a walk "
          "from rest, later steps accelerating by max_speed_change_per_step, " + _OURS),
    _spec("limits", "max_step_length_change_rel", "l1", 0.15, 0.01, 0.5,
          "§2.4 principle 1; the largest step-length change from one step to the next, " + _OURS),
    _spec("limits", "parameter_consistency_tolerance", "1", 0.01, 1e-6, 0.2,
          "§3 v = sl·sf must hold when all three are given; relative tolerance " + _OURS),
    # -- timing (section 4.2, 4.3)
    _spec("timing", "swing1_end_fraction", "1", 0.5, 0.2, 0.8,
          "§4.3: swing1 ends 'at about 50 % of the time for the swing'"),
    _spec("timing", "swing2_end_fraction", "1", 0.85, 0.5, 0.98,
          "§4.3: swing2 ends 'about 85 % into the swing'"),
    _spec("timing", "theta1_torque_off_fraction", "1", 0.4, 0.05, 1.0,
          "§4.2: F_θ1 is 'a step input torque which is turned off at 0.4·t_step'"),
    # -- step symmetry and the kinematic foot (section 3, eq. 3; section 4.2, 4.3)
    _spec("foot", "theta5_impact", "deg", 90.0, 60.0, 120.0,
          "§3 eq. 3: 'θ5 at impact is specified as one of the locomotion attributes'; ERRATA open "
          "choice: angle between leg axis and the foot's long axis, neutral ≈ 90°"),
    _spec("foot", "heel_strike_hip_lead", "1", 0.045, 0.0, 0.1,
          "§3 eq. 3 puts the hip half-way along the step at heel strike (0 here); how far ahead of "
          "half-way it is, as a fraction of the step length, at dimensionless speeds of 0.45 and "
          "more (5 km/h on a 1.8 m body; in proportion when slower): people's hip is nearer the "
          "leading foot, their trailing foot already on its ball (the hip higher, the trailing heel "
          "up: docs/human-gait.md, 'The hip ahead of mid-step'), " + _OURS),
    _spec("foot", "theta6_impact", "deg", 0.0, -30.0, 30.0,
          "§4.3: the metatarsal angle at heel strike is 'specified as locomotion attributes'"),
    _spec("foot", "foot_flat_fraction", "1", 0.08, 0.02, 0.2,
          "§4.2: the normal period's foot 'rotates around the heel until it is flat'; when (fraction "
          "of the cycle after heel strike; about 8 % in people) " + _OURS),
    _spec("foot", "heel_off_theta5", "deg", 105.0, 90.0, 130.0,
          "§4.2: 'the normal period ends when the ankle angle θ5 reaches a limiting value'; θ5 from "
          "the shank's axis to the foot's, 90° neutral, more as the shank leans over the flat foot "
          "(8-15° of dorsiflexion in people's terminal stance; the knee's schedule usually lifts the "
          "heel first); value " + _OURS),
    _spec("foot", "meta_off_theta6", "deg", 30.0, 0.0, 60.0,
          "§4.2: 'as soon as θ6 reaches a limit, the meta-off period is entered'"),
    _spec("foot", "terminal_stance_knee_flexion", "deg", 5.0, 0.5, 20.0,
          "§4.2 heel-off period (what the foot does after heel-off is not in the paper): the least "
          "knee flexion of single support; where the flat foot would straighten the leg further the "
          "heel rises (people: about 5° in terminal stance), " + _OURS),
    _spec("foot", "knee_flexion_lead", "1", 0.24, 0.05, 0.4,
          "§4.2 heel-off and meta-off periods: when the knee starts flexing for push-off, as a "
          "fraction of the cycle before toe-off (people: from about 35-40 % of the cycle; 0.24 keeps "
          "the trailing thigh at people's -18 to -20° at 5 km/h with the hip's lead), " + _OURS),
    _spec("foot", "toe_off_knee_flexion", "deg", 40.0, 5.0, 70.0,
          "§4.2 meta-off ends at toe-off, where swing1 starts; the knee flexion there, which fixes the "
          "foot's pitch (people: 35-40° at the end of pre-swing), " + _OURS),
    # -- swing (section 4.3)
    _spec("swing", "toe_clearance", "m", 0.015, 0.0, 0.1,
          "§4.3 swing2 recovery 'until the foot clears the ground'; toe clearance is one of the "
          "paper's attributes, value " + _OURS),
    _spec("swing", "swing_peak_position", "1", 0.3, 0.1, 0.7,
          "§4.3 curve P: 'C amounts to about 30% of the value for D'"),
    _spec("swing", "ankle_peak_height_rel", "l1", 0.20, 0.02, 0.5,
          "§4.3 curve P: a_max 'chosen somewhat arbitrarily'; a_max at 0 km/h, " + _OURS),
    _spec("swing", "ankle_peak_height_speed_slope", "l1/(km/h)", 0.01, 0.0, 0.05,
          "§4.3 curve P: 'the faster the walk, the smaller a_max'; slope " + _OURS),
    _spec("swing", "swing1_torque_time_constant", "1", 0.6, 0.02, 10.0,
          "§4.3: swing1 hip torque is 'a decaying exponential function'; time constant as a "
          "fraction of the swing1 duration (with the thigh at rest at t1 the torque runs from a "
          "pull at toe-off to a brake at t1; 0.6 makes the two about equal, the least peak: "
          "1.47 N m/kg at 6 km/h, 1.59 at 1.0, 1.53 at 0.5), " + _OURS),
    _spec("swing", "swing2_knee_time_constant", "1", 4.0, 0.02, 10.0,
          "§4.3: swing2 knee torque 'is a decaying exponential function'; time constant as a "
          "fraction of the swing2 duration (with the knee at rest at t2, a slow decay lets it "
          "extend softly), " + _OURS),
    _spec("swing", "knee_rate_at_t1", "1", 0.95, 0.0, 1.8,
          "§4.3 curve P: the knee's extension rate at t1, set by curve P's slope at D, as a "
          "fraction of the mean rate swing2 extends it at (the paper's slope 0 leaves swing2 a "
          "rest-to-rest extension, its knee torque's reaction pushing the held thigh back; 0.95 "
          "is about 320 deg/s at 5 km/h, where people's knee extends at 250-350 deg/s; at 0.65 "
          "swing2 started with a knee acceleration above 10000 deg/s^2, a rate jump over 100 "
          "deg/s a frame at 100 fps; at 2 swing2 would only brake), " + _OURS),
    _spec("swing", "terminal_swing_retraction", "deg", 0.0, 0.0, 15.0,
          "§4.3: the hip angle 'reaches a maximum' at t1 and holds in swing2; how far that peak is "
          "ahead of the heel-strike angle (eq. 3), which the hold retracts to from about the middle "
          "of swing2, as people's thighs do in terminal swing (the heel and the ankle higher, at "
          "about 0.17 N m/kg more peak hip torque per degree at 5 km/h); a step whose swing ankle "
          "would pass below l9 takes more, the least that clears (docs/human-gait.md), " + _OURS),
    _spec("swing", "hip_hold_frequency", "Hz", 1.2, 0.1, 20.0,
          "§4.3 swing2: hip torque 'a spring and damping model to hold the thigh in place'; "
          "natural frequency (swing3's peak hip torque, the hold plus the constant moment at t2, "
          "1.37 N m/kg at 6 km/h, 1.65 at 1.5 Hz, 1.92 at 2), " + _OURS),
    _spec("swing", "hip_hold_damping_ratio", "1", 1.0, 0.0, 5.0,
          "§4.3 swing2 hip spring-damper; damping ratio " + _OURS),
    # -- stance (section 4.2, eq. 4)
    _spec("stance", "leg_frequency", "Hz", 3.0, 0.1, 20.0,
          "§4.2 eq. 4 (lost, ERRATA 8): F_w spring k_w; natural frequency " + _OURS),
    _spec("stance", "leg_damping_ratio", "1", 0.3, 0.0, 5.0,
          "§4.2 eq. 4: F_w damper v_w; damping ratio " + _OURS),
    _spec("stance", "trunk_frequency", "Hz", 1.5, 0.1, 20.0,
          "§4.2: 'the upper body is balanced by the torque F_θ2 … a simple spring and damping "
          "model'; natural frequency " + _OURS),
    _spec("stance", "trunk_damping_ratio", "1", 0.8, 0.0, 5.0,
          "§4.2 F_θ2 spring-damper; damping ratio " + _OURS),
    _spec("stance", "trunk_lean", "deg", 0.0, -30.0, 30.0,
          "§4.2 F_θ2 spring rest angle (θ2 > 0 leans forward); " + _OURS),
    _spec("stance", "hip_height_gain", "m/m", 10.0, 0.0, 100.0,
          "§4.2: 'if it drops too low, pa is increased'; gain of pa on the hip-height error, " + _OURS),
    _spec("stance", "hip_height_rate_gain", "s", 0.05, 0.0, 10.0,
          "§4.2 pa monitoring; gain on the hip vertical velocity, " + _OURS),
    _spec("stance", "midstance_leg_shortening", "l1", 0.004, 0.0, 0.2,
          "§4.2: 'the leg does not shorten much after heel strike'; target shortening, " + _OURS),
    _spec("stance", "hip_rise_fraction", "1", 0.5, 0.1, 0.9,
          "§4.2: the hip 'prescribes a vertical sinusoidal curve'; the fraction of the step over which "
          "it rises from its heel-strike height (0.5 with hip_fall_fraction 0.5: the sinusoid peaking at "
          "mid-step), " + _OURS),
    _spec("stance", "hip_fall_fraction", "1", 0.45, 0.1, 0.9,
          "§4.2 the hip's vertical sinusoid; the fraction of the step over which it falls to the next "
          "heel strike (0.5: the paper's sinusoid; less: it holds its height into terminal stance, as "
          "people's hip does while the heel rises), " + _OURS),
    _spec("stance", "hip_fall_power", "1", 1.5, 1.0, 3.0,
          "§4.2 the hip's vertical sinusoid; the fall's raised cosine runs in 1 - (1 - r)^power of the "
          "fraction r of the fall ahead (1: the paper's sinusoid; more: the hip comes down gently in "
          "terminal stance, no faster than the rising heel keeps the knee on its schedule, and "
          "steeply in pre-swing), " + _OURS),
    _spec("stance", "min_hip_excursion_rel", "l1", 0.01, 0.0, 0.2,
          "§4.2: the hip 'prescribes a vertical sinusoidal curve'; minimum excursion, " + _OURS),
    # -- determinants of gait and upper body (section 4.2, 2.4 principle 3)
    _spec("determinants", "pelvic_rotation", "deg", 4.0, 0.0, 20.0,
          "§4.2: pelvic rotation (transverse plane) about the stance hip, each way, largest at heel "
          "strike (the landing leg's hip l0 sin of it ahead), 0 at mid-step; it carries the swing "
          "leg's hip and splits the step in eq. 3 (people at 5 km/h: about 4-5 deg each way, Kadaba "
          "et al. 1990, Perry & Burnfield; docs/human-gait.md); value " + _OURS),
    _spec("determinants", "pelvic_list", "deg", 5.0, 0.0, 20.0,
          "§4.2, fig. 9: pelvic list (coronal plane) about the stance hip, the swing side down, "
          "largest at mid-step, 0 at heel strike; it lowers the swing leg's hip (people: about 4-5 "
          "deg, Kadaba et al. 1990's obliquity, Perry & Burnfield); none in a walk's closing step, "
          "which stops level; value " + _OURS),
    _spec("determinants", "pelvic_lateral_shift", "m", 0.02, 0.0, 0.1,
          "§4.2: lateral displacement, 'a maximum shortly after toe-off'; value " + _OURS),
    _spec("determinants", "foot_lateral_distance", "m", 0.08, 0.0, 0.4,
          "§5 attributes: lateral distance between the feet (their centrelines, docs/body.md); value " + _OURS),
    _spec("determinants", "arm_swing_amplitude", "deg", 15.0, 0.0, 60.0,
          "§2.4 principle 3: 'the arms … swing forward with the opposite legs'; amplitude " + _OURS),
]

#: The registry: attribute name -> :class:`AttributeSpec`, in documentation order.
ATTRIBUTES: Mapping[str, AttributeSpec] = MappingProxyType({s.name: s for s in _SPECS})

#: The attributes a walk may change from one step to the next (a schedule entry's ``attributes``,
#: the playground's sliders): the determinants of gait that shape a step's kinematics (§4.2; the
#: pelvis turns and lists per step, with zero rate at heel strike, and the rotation each step ends
#: with is the one the next starts from) and the toe clearance swing2 keeps. The others are the
#: walker's over a whole walk, as in the paper: the envelope's limits, the foot-period and timing
#: fractions and the controllers' springs, which eq. 1-3 and the step-to-step checks read across
#: steps.
STEP_ATTRIBUTES: tuple = ("pelvic_rotation", "pelvic_list", "pelvic_lateral_shift", "arm_swing_amplitude",
                          "toe_clearance")

#: Registered and validated, but nothing in the package reads them yet, so they do not change a
#: walk (the pelvis issue will make them act). Remove a name when it acts.
NOT_USED_YET: frozenset = frozenset()

# Pairs (lower, upper) that must stay strictly ordered whatever the overrides.
_ORDERED_PAIRS = (("sf_min", "sf_max"), ("speed_min", "speed_max"),
                  ("step_length_min_rel", "step_length_max_rel"),
                  ("swing1_end_fraction", "swing2_end_fraction"))


def _unknown_name(name) -> ConfigError:
    close = difflib.get_close_matches(str(name), list(ATTRIBUTES), n=3, cutoff=0.6)
    allowed = ("a registered attribute name, close matches: " + ", ".join(close) if close
               else "one of " + ", ".join(ATTRIBUTES))
    return ConfigError(out_of_range(f"attributes.{name}", name, allowed))


class LocomotionAttributes:
    """An immutable, validated set of locomotion attribute values (units as in :data:`ATTRIBUTES`).

    Read a value as an attribute (``attrs.toe_clearance``) or with :meth:`get`; angles come in
    degrees, :meth:`rad` gives radians. Build one with :meth:`defaults` and
    :meth:`with_overrides`; the constructor takes a complete mapping of every name.
    """

    __slots__ = ("_values",)

    def __init__(self, values: Mapping[str, float]):
        if not isinstance(values, Mapping):
            raise ConfigError(out_of_range("attributes", values, "a mapping of attribute name to number"))
        for name in values:
            if name not in ATTRIBUTES:
                raise _unknown_name(name)
        missing = [n for n in ATTRIBUTES if n not in values]
        if missing:
            raise ConfigError(out_of_range("attributes", f"no value for {', '.join(missing)}",
                                           "a value for every registered attribute"))
        checked = {n: ATTRIBUTES[n].check(values[n]) for n in ATTRIBUTES}
        for lo, hi in _ORDERED_PAIRS:
            if not checked[lo] < checked[hi]:
                raise ConfigError(out_of_range(f"attributes.{lo}", checked[lo],
                                               f"less than attributes.{hi} = {checked[hi]:g}"))
        object.__setattr__(self, "_values", MappingProxyType(checked))

    @classmethod
    def defaults(cls) -> "LocomotionAttributes":
        """Every attribute at its registered default."""
        return cls({n: s.default for n, s in ATTRIBUTES.items()})

    def with_overrides(self, overrides: Mapping[str, float] | None) -> "LocomotionAttributes":
        """A copy with some values replaced; names and ranges are checked (ConfigError)."""
        if overrides is None:
            return self
        if not isinstance(overrides, Mapping):
            raise ConfigError(out_of_range("attributes", overrides, "a mapping of attribute name to number"))
        for name in overrides:
            if name not in ATTRIBUTES:
                raise _unknown_name(name)
        return type(self)({**self._values, **overrides})

    def get(self, name: str) -> float:
        """The value of ``name`` in its registered unit; ConfigError for an unknown name."""
        if name not in ATTRIBUTES:
            raise _unknown_name(name)
        return self._values[name]

    def rad(self, name: str) -> float:
        """The value of an angle attribute (unit ``deg``) in radians."""
        spec = ATTRIBUTES.get(name)
        if spec is None:
            raise _unknown_name(name)
        if spec.unit != "deg":
            raise ConfigError(out_of_range(f"attributes.{name}", f"unit {spec.unit}", "an angle in deg for rad()"))
        return math.radians(self._values[name])

    def as_dict(self) -> dict[str, float]:
        """Every value by name, in registry order (a plain, JSON-ready dict)."""
        return dict(self._values)

    def overrides(self) -> dict[str, float]:
        """Only the values that differ from the registered defaults."""
        return {n: v for n, v in self._values.items() if v != ATTRIBUTES[n].default}

    def __getattr__(self, name: str) -> float:
        # Only reached when normal lookup fails; private names must fail normally so that
        # copy/pickle machinery does not recurse before _values is set.
        if name.startswith("_") or name not in ATTRIBUTES:
            raise AttributeError(f"{type(self).__name__!s} has no attribute {name!r}")
        return self._values[name]

    def __setattr__(self, name, value):
        raise AttributeError(f"{type(self).__name__} is immutable; use with_overrides()")

    def __delattr__(self, name):
        raise AttributeError(f"{type(self).__name__} is immutable")

    def __dir__(self):
        return sorted(set(super().__dir__()) | set(ATTRIBUTES))

    def __eq__(self, other):
        if not isinstance(other, LocomotionAttributes):
            return NotImplemented
        return dict(self._values) == dict(other._values)

    def __hash__(self):
        return hash(tuple(self._values.items()))

    def __reduce__(self):
        return (type(self), (dict(self._values),))

    def __repr__(self):
        changed = self.overrides()
        inner = ", ".join(f"{k}={v!r}" for k, v in changed.items()) if changed else "defaults"
        return f"{type(self).__name__}({inner})"


def resolve(attributes: LocomotionAttributes | Mapping[str, float] | None) -> LocomotionAttributes:
    """Accept ``None`` (defaults), a mapping of overrides, or a ready :class:`LocomotionAttributes`."""
    if attributes is None:
        return LocomotionAttributes.defaults()
    if isinstance(attributes, LocomotionAttributes):
        return attributes
    return LocomotionAttributes.defaults().with_overrides(attributes)


def markdown_table() -> str:
    """The text of docs/attributes.md, generated from the registry."""
    lines = [
        "# Locomotion attributes",
        "",
        "<!-- Generated from klaw_ocp.gait.attributes.ATTRIBUTES; do not edit by hand. Regenerate with",
        "     python -c \"from klaw_ocp.gait.attributes import markdown_table as t; print(t(), end='')\" > docs/attributes.md",
        "     tests/test_attributes.py fails when this file and the registry disagree. -->",
        "",
        "The values that individualise a walk (paper section 3 and section 5). Override any of them",
        "in a config's `attributes:` mapping. Units: `deg` angles (radians internally), `l1` a",
        "multiple of the leg length l1 = l3 + l4, `1` a plain fraction. Ranges are inclusive.",
        "Column *walk*: **per step** marks an attribute that may change from one step to the next",
        "(a schedule entry's `attributes`, e.g. `walk.schedule: [{step: 4, attributes: {pelvic_list: 8}}]`,",
        "moving linearly between two entries as the locomotion parameters do; the playground's",
        "determinant sliders); the others are the walker's over a whole walk. **not used yet** marks",
        "an attribute that is validated but that nothing in `src/klaw_ocp` reads yet, so setting it",
        "does not change the walk.",
    ]
    group = None
    for spec in ATTRIBUTES.values():
        if spec.group != group:
            group = spec.group
            lines += ["", f"## {group}", "", "| name | unit | default | range | source | walk |",
                      "|---|---|---|---|---|---|"]
        walk = ("**not used yet**" if spec.name in NOT_USED_YET
                else "**per step**" if spec.name in STEP_ATTRIBUTES else "")
        lines.append(f"| `{spec.name}` | {spec.unit} | {spec.default:g} | {spec.low:g} to "
                     f"{spec.high:g} | {spec.paper} | {walk} |")
    return "\n".join(lines) + "\n"
