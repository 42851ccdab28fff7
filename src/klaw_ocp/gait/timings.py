"""State-phase timings: section 3, eq. 2, and the subphase boundaries of sections 4.2 and 4.3.

A cycle is two steps; a step is one double-support state plus one single-support state
(fig. 3). With sf in steps/min the paper's ``t_cycle = 2/sf`` is in minutes (ERRATA 9); in
seconds::

    t_cycle = 120 / sf          t_step = 60 / sf
    t_ds    = (-0.16·sf + 29.08) · t_cycle / 100      (double support, Inman's linear law)
    t_stance = t_step + t_ds    t_swing = t_step - t_ds                        (eq. 2)

t_ds vanishes at sf = 29.08/0.16 = 181.75 steps/min, where walking becomes running; this
matches the paper's sf_max = 182. The swing subphases end at 50 % and 85 % of t_swing
(section 4.3) and the stance hip torque F_θ1 is switched off at 0.4·t_step (section 4.2); the
fractions are locomotion attributes.
"""
from __future__ import annotations

from dataclasses import asdict, dataclass

from ..errors import ConfigError, GaitLimitError, finite_real, out_of_range
from .attributes import LocomotionAttributes, resolve

#: Coefficients of the double-support law t_ds/t_cycle [%] = DS_SLOPE·sf + DS_OFFSET (section 3).
DS_SLOPE = -0.16
DS_OFFSET = 29.08
#: The step frequency at which t_ds reaches 0 (walking becomes running), steps/min.
SF_DS_ZERO = -DS_OFFSET / DS_SLOPE


@dataclass(frozen=True)
class StateTimings:
    """Durations of one step, all in seconds (eq. 2).

    ``t_swing1_end`` and ``t_swing2_end`` are measured from toe-off (the start of the swing);
    ``t_theta1_off`` is measured from heel strike (the start of the stance simulation).
    """

    t_cycle: float
    t_step: float
    t_ds: float
    t_stance: float
    t_swing: float
    t_swing1_end: float
    t_swing2_end: float
    t_theta1_off: float

    def as_dict(self) -> dict[str, float]:
        """Every duration, keys suffixed ``_s`` (seconds)."""
        return {f"{k}_s": v for k, v in asdict(self).items()}


def state_phase_timings(step_frequency_spm, attributes: LocomotionAttributes | None = None,
                        *, field: str = "walk.step_frequency") -> StateTimings:
    """The timings of one step at step frequency ``step_frequency_spm`` (steps/min).

    Raises:
        ConfigError: sf is not a finite number > 0.
        GaitLimitError: sf ≥ 181.75 steps/min, where the double support t_ds is no longer > 0.
    """
    sf = step_frequency_spm
    if finite_real(sf) is None or sf <= 0:
        raise ConfigError(out_of_range(field, sf, "a finite number > 0 in steps/min"))
    sf = float(sf)
    attrs = resolve(attributes)
    t_cycle = 120.0 / sf
    t_step = 60.0 / sf
    t_ds = (DS_SLOPE * sf + DS_OFFSET) * t_cycle / 100.0
    if t_ds <= 0.0:
        raise GaitLimitError(f"{field}: got {sf:.6g} steps/min, allowed below {SF_DS_ZERO:g} "
                             f"steps/min (eq. 2: the double support t_ds = {t_ds:.3g} s is not > 0, "
                             f"walking would become running)")
    t_swing = t_step - t_ds
    return StateTimings(
        t_cycle=t_cycle,
        t_step=t_step,
        t_ds=t_ds,
        t_stance=t_step + t_ds,
        t_swing=t_swing,
        t_swing1_end=attrs.swing1_end_fraction * t_swing,
        t_swing2_end=attrs.swing2_end_fraction * t_swing,
        t_theta1_off=attrs.theta1_torque_off_fraction * t_step,
    )
