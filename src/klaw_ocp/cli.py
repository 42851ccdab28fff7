"""The ``klaw-ocp`` command line.

Subcommands are registered in :data:`SUBCOMMANDS` (name -> :class:`Subcommand`); adding one is a
function that configures its argparse sub-parser, a handler ``(args) -> exit code``, and one
dict entry. ``plan`` runs the paper's high-level concepts (section 3: eq. 1 parameters, eq. 2
timings, eq. 3 step constraints) for one step given on the command line or for every step of a
configured walk.

Errors: every :class:`klaw_ocp.errors.KlawError` becomes one line on stderr,
``klaw-ocp: error: <message>``, and exit code 2 (argparse's own usage errors also exit 2).
"""
from __future__ import annotations

import argparse
import json
import math
import os
import sys
from dataclasses import dataclass, replace
from typing import Callable

from .body import Body
from .errors import ConfigError, KlawError
from .gait import LocomotionAttributes, StepPlan, plan_steps

PROG = "klaw-ocp"
DEFAULT_HEIGHT_M = 1.8
DEFAULT_MASS_KG = 80.0
EXIT_USAGE = 2


@dataclass(frozen=True)
class Subcommand:
    """One ``klaw-ocp <name>`` command: its help line, argument setup and handler."""

    help: str
    configure: Callable[[argparse.ArgumentParser], None]
    handler: Callable[[argparse.Namespace], int]


# ------------------------------------------------------------------------------------- plan

def _configure_plan(p: argparse.ArgumentParser) -> None:
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


def _cmd_plan(args: argparse.Namespace) -> int:
    flags = {"--speed": args.speed, "--step-length": args.step_length,
             "--step-frequency": args.step_frequency, "--height": args.height, "--mass": args.mass}
    given = [k for k, v in flags.items() if v is not None]
    if args.config is not None:
        if given:
            raise ConfigError(f"plan: got CONFIG together with {', '.join(given)}, allowed either a "
                              f"CONFIG file or command-line parameters")
        from .config import load_config  # only this path needs yaml and pydantic
        cfg = load_config(args.config)
        body, attrs, plans = cfg.body_model(), cfg.attributes_model(), cfg.plan()
        header = {"name": cfg.name}
    else:
        if args.speed is None and args.step_length is None and args.step_frequency is None:
            raise ConfigError("plan: got no locomotion parameter, allowed a CONFIG file or at least "
                              "one of --speed, --step-length, --step-frequency")
        body = Body(height=DEFAULT_HEIGHT_M if args.height is None else args.height,
                    mass=DEFAULT_MASS_KG if args.mass is None else args.mass)
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
        print(_format_table(body, plans, header.get("name")))
    return 0


def _body_line(body: Body) -> str:
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
        ("hip", f"({c.hip_x:.4f}, {c.hip_y:.4f})", "m"),
        ("stance ankle (origin)", f"({c.ankle_x:.4f}, {c.ankle_y:.4f})", "m"),
        ("landing heel x", f"{c.heel_x:.4f}", "m"),
    ]
    lines = [_body_line(body)]
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


def _format_table(body: Body, plans: list[StepPlan], name: str | None) -> str:
    cells = [[format(get(s), fmt) for _, _, get, fmt in _COLUMNS] for s in plans]
    heads = [h for h, _, _, _ in _COLUMNS]
    units = [f"[{u}]" if u else "" for _, u, _, _ in _COLUMNS]
    widths = [max(len(h), len(u), *(len(r[i]) for r in cells)) for i, (h, u) in enumerate(zip(heads, units))]
    row = lambda items: "  ".join(x.rjust(w) for x, w in zip(items, widths))  # noqa: E731
    total = plans[-1].t_start + plans[-1].timings.t_step
    title = (f"Walk {name!r}: " if name else "Walk: ") + f"{len(plans)} steps, {total:.2f} s"
    lines = [title, _body_line(body), "", row(heads), row(units)]
    lines += [row(r) for r in cells]
    lines += ["", "sw1_end/sw2_end: swing subphase ends after toe-off; w, theta1, theta3, hip_y at "
                  "heel strike (eq. 3); ankle_x: stance origin."]
    return "\n".join(lines)


# -------------------------------------------------------------------------------------- run

EXIT_NOT_CONVERGED = 1


def _configure_run(p: argparse.ArgumentParser) -> None:
    p.description = ("Simulate the configured walk step by step and write summary.json and "
                     "dynamics.csv to --out (default results/<name>/). A subphase that does not "
                     "converge is reported on one line (step, subphase, residual); the steps "
                     "completed before it are still written, and the exit code is 1.")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<name>/)")
    p.add_argument("--method", choices=("multiple-shooting", "plain-shooting"),
                   help="solver mode (default: the config's solver.method)")
    p.add_argument("--stance", choices=("monitored", "tracking"),
                   help="stance formulation: the paper's monitored pa, or pa optimised over the grid "
                        "to track the hip sinusoid (multiple shooting only; default: solver.stance)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _cmd_run(args: argparse.Namespace) -> int:
    from .config import load_config
    from .errors import ConvergenceError
    from .io import write_walk
    from .walk import simulate_walk, walk_spec

    config = load_config(args.config)
    out = args.out or config.output_dir()
    spec = walk_spec(config, args.method)
    if args.stance:
        spec = replace(spec, stance=args.stance)
    try:
        walk = simulate_walk(spec, progress=not args.quiet)
    except ConvergenceError as exc:
        paths = write_walk(exc.partial, out)
        print(f"{PROG}: error: {exc}; {len(exc.partial.steps)} completed step(s) written to "
              f"{paths['summary'].parent}", file=sys.stderr)
        return EXIT_NOT_CONVERGED
    paths = write_walk(walk, out)
    rtf = walk.duration / walk.wall_s if walk.wall_s else float("inf")
    print(f"{spec.name}: {len(walk.steps)} steps, {walk.duration:.2f} s of walking in {walk.wall_s:.2f} s "
          f"({rtf:.1f}x real time, {spec.method}, {spec.stance} stance); wrote {paths['summary']} and {paths['dynamics']}")
    return 0


# ------------------------------------------------------------------------------------ sweep

def _configure_sweep(p: argparse.ArgumentParser) -> None:
    p.description = ("Walk every combination of the --vary values (their Cartesian product, the "
                     "first path varying slowest) and write sweep.csv (one row per walk and method) "
                     "and sweep.png (a convergence and wall-time map) to --out (default "
                     "results/<name>-sweep/). Every combination is validated before any walk "
                     "starts; a walk that fails does not stop the others. Exit code 0 if every "
                     "walk converged, 1 otherwise, 2 for bad input. See docs/sweep.md.")
    p.add_argument("config", metavar="CONFIG", help="experiment YAML file (see configs/)")
    p.add_argument("--vary", action="append", required=True, metavar="PATH=VALUES",
                   help="a dotted config path (walk.speed, body.height, attributes.pelvic_list, "
                        "solver.intervals, ...) and its values: a comma list of YAML scalars "
                        "(1,3,5 or true,false) or a range start:stop:step that includes stop when "
                        "it is on the grid (0.5:8:0.5); repeat for a grid")
    p.add_argument("--method", choices=("multiple-shooting", "plain-shooting", "both"),
                   help="solver mode(s) (default: each combination's solver.method)")
    p.add_argument("--workers", type=int, metavar="N",
                   help="local worker processes (default: the number of CPUs; 1 runs in this process)")
    p.add_argument("--scheduler", metavar="ADDRESS",
                   help='run the walks on a dask.distributed cluster (tcp://host:8786); needs '
                        'pip install -e ".[cluster]"')
    p.add_argument("--out", metavar="DIR", help="output folder (default: results/<name>-sweep/)")
    p.add_argument("--quiet", action="store_true", help="no progress bar")


def _cmd_sweep(args: argparse.Namespace) -> int:
    from .sweep import counts, default_out_dir, parse_vary, run_sweep, summary_line, write_sweep

    vary: dict[str, list] = {}
    for text in args.vary:
        path, values = parse_vary(text)
        if path in vary:
            raise ConfigError(f"--vary {path}: got the path twice, allowed each path once")
        vary[path] = values
    rows = run_sweep(args.config, vary, methods=args.method, workers=args.workers,
                     scheduler=args.scheduler, progress=not args.quiet and sys.stderr.isatty())
    out = args.out or default_out_dir(args.config)
    paths = write_sweep(rows, list(vary), out, title=f"{PROG} sweep {os.path.basename(args.config)}")
    print(summary_line(rows, paths))
    n = counts(rows)
    return 0 if n["ok"] == len(rows) else EXIT_NOT_CONVERGED


# ----------------------------------------------------------------------------- registry, main

#: Every subcommand by name. Another command is one more entry here.
SUBCOMMANDS: dict[str, Subcommand] = {
    "plan": Subcommand(help="plan a walk: parameters (eq. 1), timings (eq. 2), constraints (eq. 3)",
                       configure=_configure_plan, handler=_cmd_plan),
    "run": Subcommand(help="simulate a configured walk and write its result files",
                      configure=_configure_run, handler=_cmd_run),
    "sweep": Subcommand(help="walk a grid of config values and write sweep.csv and sweep.png",
                        configure=_configure_sweep, handler=_cmd_sweep),
}


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG, description="KLAW (Bruderlin & Calvert 1989): goal-directed dynamic walking.")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    for name, command in SUBCOMMANDS.items():
        p = sub.add_parser(name, help=command.help)
        command.configure(p)
        p.set_defaults(handler=command.handler)
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run ``klaw-ocp``; returns the exit code (0 ok, 1 a subphase did not converge, 2 bad input)."""
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exc:  # argparse reports usage errors itself and exits 2 (--help: 0)
        return exc.code if isinstance(exc.code, int) else EXIT_USAGE
    handler = getattr(args, "handler", None)
    if handler is None:
        parser.print_usage(sys.stderr)
        print(f"{PROG}: error: a COMMAND is required, allowed: {', '.join(SUBCOMMANDS)}", file=sys.stderr)
        return EXIT_USAGE
    try:
        return handler(args)
    except KlawError as exc:
        message = " ".join(str(exc).split("\n"))
        print(f"{PROG}: error: {message}", file=sys.stderr)
        return EXIT_USAGE
    except BrokenPipeError:
        # The reader (e.g. `| head`) closed the pipe: stop quietly, as the Python docs advise,
        # and keep the interpreter from failing again when it flushes stdout at exit.
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
        return 1


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
