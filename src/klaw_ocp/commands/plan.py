"""``klaw-ocp plan``: the paper's high-level concepts for one step given on the command line or for
every step of a configured walk (section 3: eq. 1 parameters, eq. 2 timings, eq. 3 step
constraints). :func:`format_table` is also what ``validate`` prints."""
from __future__ import annotations

import argparse
import json
import math

from ..body import Body
from ..errors import ConfigError
from ..gait import LocomotionAttributes, StepPlan, plan_steps

HELP = "plan a walk: parameters (eq. 1), timings (eq. 2), constraints (eq. 3)"
DEFAULT_HEIGHT_M = 1.8
DEFAULT_MASS_KG = 80.0


def configure(p: argparse.ArgumentParser) -> None:
    p.description = ("Complete the locomotion parameters (eq. 1), and print the state-phase "
                     "timings (eq. 2) and the step constraints at heel strike (eq. 3). Give a "
                     "CONFIG file for every step of a configured walk, or one to three of "
                     "--speed/--step-length/--step-frequency for one step.")
    p.add_argument("config", nargs="?", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--speed", type=float, metavar="KMH", help="walking speed v, km/h")
    p.add_argument("--step-length", type=float, metavar="M", help="step length sl, m")
    p.add_argument("--step-frequency", type=float, metavar="SPM", help="step frequency sf, steps/min")
    p.add_argument("--height", type=float, metavar="M", help=f"body height, m (default {DEFAULT_HEIGHT_M})")
    p.add_argument("--mass", type=float, metavar="KG", help=f"body mass, kg (default {DEFAULT_MASS_KG:g})")
    p.add_argument("--json", action="store_true", help="print one JSON object instead of a table")
    p.epilog = "example: klaw-ocp plan --speed 5 --step-length 0.5 --height 1.7 --mass 65"


def handle(args: argparse.Namespace) -> int:
    flags = {"--speed": args.speed, "--step-length": args.step_length,
             "--step-frequency": args.step_frequency, "--height": args.height, "--mass": args.mass}
    given = [k for k, v in flags.items() if v is not None]
    if args.config is not None:
        if given:
            raise ConfigError(f"plan: got CONFIG together with {', '.join(given)}, allowed either a "
                              f"CONFIG file or command-line parameters")
        from ..config import load_config  # only this path needs yaml and pydantic
        cfg = load_config(args.config)
        body, attrs, plans = cfg.body_model(), cfg.attributes_model(), cfg.plan()
        header = {"name": cfg.name}
    else:
        # the flags in the order they are listed: a bad --height is named even without a speed
        body = Body(height=DEFAULT_HEIGHT_M if args.height is None else args.height,
                    mass=DEFAULT_MASS_KG if args.mass is None else args.mass)
        if args.speed is None and args.step_length is None and args.step_frequency is None:
            raise ConfigError("plan: got no locomotion parameter, allowed a CONFIG file or at least "
                              "one of --speed, --step-length, --step-frequency")
        attrs = LocomotionAttributes.defaults()
        request = {"speed": args.speed, "step_length": args.step_length,
                   "step_frequency": args.step_frequency}
        plans = plan_steps(body, request, n_steps=1, attributes=attrs)
        header = {}
    if args.json:
        print(json.dumps({**header, "body": body.as_dict(), "attributes": attrs.as_dict(),
                          "steps": [p.as_dict() for p in plans]}, indent=2))
    elif len(plans) == 1 and args.config is None:
        print(_format_single(body, plans[0]))
    else:
        print(format_table(body, plans, header.get("name")))
    return 0


def body_line(body: Body) -> str:
    return (f"Body: height {body.height:.3g} m, mass {body.mass:.4g} kg, "
            f"leg length l1 = {body.l1:.4f} m")


def _format_single(body: Body, plan: StepPlan) -> str:
    p, t, c = plan.parameters, plan.timings, plan.constraints
    deg = math.degrees
    rows = [
        ("Locomotion parameters (eq. 1)", None, None),
        ("speed v", f"{p.speed_kmh:.4f}", "km/h"),
        ("step length sl", f"{p.step_length_m:.4f}", "m"),
        ("step frequency sf", f"{p.step_frequency_spm:.2f}", "steps/min"),
        ("State-phase timings (eq. 2)", None, None),
        ("t_cycle", f"{t.t_cycle:.4f}", "s"),
        ("t_step", f"{t.t_step:.4f}", "s"),
        ("t_ds (double support)", f"{t.t_ds:.4f}", "s"),
        ("t_stance", f"{t.t_stance:.4f}", "s"),
        ("t_swing", f"{t.t_swing:.4f}", "s"),
        ("swing1 ends", f"{t.t_swing1_end:.4f}", "s after toe-off"),
        ("swing2 ends", f"{t.t_swing2_end:.4f}", "s after toe-off"),
        ("F_theta1 off", f"{t.t_theta1_off:.4f}", "s after heel strike"),
        ("Step constraints at heel strike (eq. 3)", None, None),
        ("w (stance leg)", f"{c.w:.4f}", f"m  (l1 = {body.l1:.4f} m)"),
        ("theta1 (stance leg)", f"{c.theta1:.4f}", f"rad  ({deg(c.theta1):.2f} deg)"),
        ("theta3 (swing thigh)", f"{c.theta3:.4f}", f"rad  ({deg(c.theta3):.2f} deg)"),
        ("hip", f"({c.hip_x:.4f}, {c.hip_y:.4f})", "m  (the stance leg's)"),
        ("hip ahead of mid-step", f"{c.hip_lead:.4f}", "m  (heel_strike_hip_lead x sl)"),
        ("w (landing leg)", f"{c.landing_w:.4f}", "m"),
        ("theta1 (landing leg)", f"{c.landing_theta1:.4f}", f"rad  ({deg(c.landing_theta1):.2f} deg)"),
        ("landing hip ahead by", f"{c.hip_shift:.4f}", "m  (l0 sin(pelvic_rotation): the pelvis's other hip)"),
        ("stance ankle (origin)", f"({c.ankle_x:.4f}, {c.ankle_y:.4f})", "m"),
        ("landing heel x", f"{c.heel_x:.4f}", "m"),
    ]
    lines = [body_line(body)]
    for label, value, unit in rows:
        if value is None:
            lines += ["", label]
        else:
            lines.append(f"  {label:<24}{value:>18}  {unit}")
    return "\n".join(lines)


_COLUMNS = [  # header, unit, getter, format
    ("step", "", lambda s: s.index, "d"),
    ("t_start", "s", lambda s: s.t_start, ".3f"),
    ("v", "km/h", lambda s: s.parameters.speed_kmh, ".3f"),
    ("sl", "m", lambda s: s.parameters.step_length_m, ".4f"),
    ("sf", "1/min", lambda s: s.parameters.step_frequency_spm, ".2f"),
    ("t_step", "s", lambda s: s.timings.t_step, ".4f"),
    ("t_ds", "s", lambda s: s.timings.t_ds, ".4f"),
    ("t_stance", "s", lambda s: s.timings.t_stance, ".4f"),
    ("t_swing", "s", lambda s: s.timings.t_swing, ".4f"),
    ("sw1_end", "s", lambda s: s.timings.t_swing1_end, ".4f"),
    ("sw2_end", "s", lambda s: s.timings.t_swing2_end, ".4f"),
    ("w", "m", lambda s: s.constraints.w, ".4f"),
    ("theta1", "rad", lambda s: s.constraints.theta1, ".4f"),
    ("theta3", "rad", lambda s: s.constraints.theta3, ".4f"),
    ("hip_y", "m", lambda s: s.constraints.hip_y, ".4f"),
    ("ankle_x", "m", lambda s: s.constraints.ankle_x, ".3f"),
]


def format_table(body: Body, plans: list[StepPlan], name: str | None) -> str:
    cells = [[format(get(s), fmt) for _, _, get, fmt in _COLUMNS] for s in plans]
    heads = [h for h, _, _, _ in _COLUMNS]
    units = [f"[{u}]" if u else "" for _, u, _, _ in _COLUMNS]
    widths = [max(len(h), len(u), *(len(r[i]) for r in cells)) for i, (h, u) in enumerate(zip(heads, units))]
    row = lambda items: "  ".join(x.rjust(w) for x, w in zip(items, widths))  # noqa: E731
    total = plans[-1].t_start + plans[-1].timings.t_step
    title = (f"Walk {name!r}: " if name else "Walk: ") + f"{len(plans)} steps, {total:.2f} s"
    lines = [title, body_line(body), "", row(heads), row(units)]
    lines += [row(r) for r in cells]
    lines += ["", "sw1_end/sw2_end: swing subphase ends after toe-off; w, theta1, theta3, hip_y at "
                  "heel strike (eq. 3); ankle_x: stance origin."]
    return "\n".join(lines)
