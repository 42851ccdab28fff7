"""Locomotion parameters: section 3, the normalizing formula (eq. 1) and the anatomical limits.

The three locomotion parameters are the speed v, the step length sl and the step frequency sf,
tied by ``v = sl·sf``. The paper's normalizing formula (eq. 1, from Inman's data) picks the
energy-saving combination for a body height H::

    sl / (sf · H) = 0.004      <=>      sf² = v / (0.004 · H)

with sl and H in m and sf in steps/min, so v = sl·sf is in m/min (ERRATA 9). The user-facing
speed is in km/h; :func:`complete_parameters` converts. From any non-empty subset of (v, sl, sf)
it completes the others, then checks the result against the limits held as locomotion
attributes (``sf_max = 182 steps/min`` is the paper's example).
"""
from __future__ import annotations

import math
import numbers
from dataclasses import dataclass

from ..body import Body
from ..errors import ConfigError, GaitLimitError, finite_real, out_of_range
from .attributes import LocomotionAttributes, resolve

#: The constant of eq. 1: sl / (sf · H) with sl and H in m and sf in steps/min (unit min/step).
NORMALIZING_CONSTANT = 0.004

#: km/h -> m/min (eq. 1 works in m/min because sf is in steps/min).
KMH_TO_M_PER_MIN = 1000.0 / 60.0


@dataclass(frozen=True)
class LocomotionParameters:
    """A complete, consistent set of locomotion parameters (section 3).

    Attributes:
        speed_kmh: forward speed v, km/h.
        step_length_m: step length sl, m (ankle to ankle, one step = half a cycle).
        step_frequency_spm: step frequency sf, steps/min.
    """

    speed_kmh: float
    step_length_m: float
    step_frequency_spm: float

    @property
    def speed_m_per_min(self) -> float:
        """v in m/min, the unit in which ``v = sl·sf`` holds (ERRATA 9)."""
        return self.speed_kmh * KMH_TO_M_PER_MIN

    @property
    def speed_m_per_s(self) -> float:
        """v in m/s."""
        return self.speed_kmh / 3.6

    def as_dict(self) -> dict[str, float]:
        return {"speed_kmh": self.speed_kmh, "step_length_m": self.step_length_m,
                "step_frequency_spm": self.step_frequency_spm}


def _positive(field: str, value, unit: str) -> float | None:
    """None stays None (not given); anything else must be a finite number > 0."""
    if value is None:
        return None
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise ConfigError(out_of_range(field, value, f"a finite number > 0 in {unit}"))
    number = finite_real(value)
    if number is None or number <= 0.0:
        raise ConfigError(out_of_range(field, value if number is None else number, f"a finite number > 0 in {unit}"))
    return number


def natural_step_length(height_m: float, speed_m_per_min: float) -> float:
    """Eq. 1's natural step length (m) at a speed (m/min): sl = v / sf with sf² = v / (0.004 · H)."""
    return math.sqrt(NORMALIZING_CONSTANT * height_m * speed_m_per_min)


def complete_parameters(body: Body, speed_kmh=None, step_length=None, step_frequency=None,
                        attributes: LocomotionAttributes | None = None, *,
                        field_prefix: str = "walk") -> LocomotionParameters:
    """Complete (v, sl, sf) from any non-empty subset with eq. 1, then check the limits.

    Args:
        body: gives the body height H of eq. 1 and the leg length l1 for the step-length limits.
        speed_kmh: v in km/h, or None.
        step_length: sl in m, or None.
        step_frequency: sf in steps/min, or None.
        attributes: the limits (defaults if None).
        field_prefix: how errors name the source, e.g. ``walk`` or ``walk.schedule[2]``.

    With all three given they must satisfy v = sl·sf within
    ``attributes.parameter_consistency_tolerance`` (relative); sl and sf are then kept and v is
    recomputed from them, because sl and sf are what the step constraints use.

    Raises:
        ConfigError: a value is not a finite number > 0, or none is given.
        GaitLimitError: the three disagree, or a completed value is outside the limits.
    """
    attrs = resolve(attributes)
    f_v, f_sl, f_sf = (f"{field_prefix}.speed", f"{field_prefix}.step_length",
                       f"{field_prefix}.step_frequency")
    v_kmh = _positive(f_v, speed_kmh, "km/h")
    sl = _positive(f_sl, step_length, "m")
    sf = _positive(f_sf, step_frequency, "steps/min")
    if v_kmh is None and sl is None and sf is None:
        raise ConfigError(out_of_range(field_prefix, "no locomotion parameter",
                                       "at least one of speed, step_length, step_frequency"))
    v = None if v_kmh is None else v_kmh * KMH_TO_M_PER_MIN  # m/min
    given = {f_v: v is not None, f_sl: sl is not None, f_sf: sf is not None}
    fields = (f_v, f_sl, f_sf)

    if v is not None and sl is not None and sf is not None:
        mismatch = abs(sl * sf - v) / v
        tol = attrs.parameter_consistency_tolerance
        if mismatch > tol:
            raise GaitLimitError(
                f"{field_prefix}: got speed {v_kmh:g} km/h, step_length {sl:g} m and step_frequency "
                f"{sf:g} steps/min, which disagree (sl·sf = {sl * sf / KMH_TO_M_PER_MIN:.4g} km/h, "
                f"{100 * mismatch:.3g} % off), allowed a mismatch of at most {100 * tol:g} % "
                f"(attributes.parameter_consistency_tolerance)")
    # the values as typed first (1e308 km/h is reported as such, not as the infinity its m/min
    # overflows to): then the completion below stays within floats (5e-324 km/h would give
    # sl = 0 and 1e308 km/h an infinite v)
    _check_limits(body, attrs, given, fields, {f_v: v_kmh, f_sl: sl, f_sf: sf})
    v, sl, sf = _completed(body.height, v, sl, sf)
    params = LocomotionParameters(speed_kmh=v / KMH_TO_M_PER_MIN, step_length_m=sl,
                                  step_frequency_spm=sf)
    _check_limits(body, attrs, given, fields, {f_v: params.speed_kmh, f_sl: params.step_length_m,
                                               f_sf: params.step_frequency_spm})
    return params


def _completed(h: float, v, sl, sf) -> tuple[float, float, float]:
    """(v in m/min, sl, sf) from those given (the others None) and eq. 1 for body height ``h``;
    with all three given, v = sl·sf (sl and sf are what the step constraints use)."""
    if sl is not None and sf is not None:
        return sl * sf, sl, sf
    if v is not None and sl is not None:
        return v, sl, v / sl
    if v is not None and sf is not None:
        return v, v / sf, sf
    if v is not None:
        sl = natural_step_length(h, v)  # eq. 1, right-hand form
        return v, sl, v / sl
    if sl is not None:
        sf = sl / (NORMALIZING_CONSTANT * h)
        return sl * sf, sl, sf
    sl = NORMALIZING_CONSTANT * h * sf
    return sl * sf, sl, sf


def _check_limits(body: Body, attrs: LocomotionAttributes, given: dict[str, bool],
                  fields: tuple[str, str, str], values: dict) -> None:
    """Raise GaitLimitError for the first of ``values`` (field -> value, None for none) outside
    its limits, user-given values first."""
    f_v, f_sl, f_sf = fields
    l1 = body.l1
    checks = [
        (f_v, values[f_v], attrs.speed_min, attrs.speed_max, "km/h", "speed_min/speed_max"),
        (f_sl, values[f_sl], attrs.step_length_min_rel * l1, attrs.step_length_max_rel * l1, "m",
         f"step_length_min_rel/step_length_max_rel × leg length l1 = {l1:.4g} m"),
        (f_sf, values[f_sf], attrs.sf_min, attrs.sf_max, "steps/min", "sf_min/sf_max"),
    ]
    # A value the user typed is the likelier culprit, so report it before derived ones.
    checks.sort(key=lambda c: not given[c[0]])
    for field, value, lo, hi, unit, source in checks:
        if value is None:
            continue
        if not lo <= value <= hi:
            origin = "" if given[field] else " (completed by eq. 1)"
            raise GaitLimitError(f"{field}: got {value:.6g} {unit}{origin}, allowed {lo:.4g} to "
                                 f"{hi:.4g} {unit} (attributes.{source})")
