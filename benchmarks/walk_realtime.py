"""Benchmark: wall time and real-time factor of a configured walk in each solver mode.

    python benchmarks/walk_realtime.py [CONFIG] [--steps N]

Prints, per mode (multiple shooting with the monitored and with the tracking stance, and plain
shooting): the one-off build time (CasADi functions and solvers, paid once per process),
the wall time of the walk after the build, and the real-time factor (simulated seconds per wall
second). The paper's reference: a 12 s walk took 37.3 s of CPU on a SUN3-50 (factor 0.32).
Timings are measured here, never asserted in tests.
"""
from __future__ import annotations

import argparse
import time
from dataclasses import replace

from klaw_ocp.config import load_config
from klaw_ocp.walk import simulate_walk, walk_spec


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("config", nargs="?", default="configs/natural_walk.yaml")
    parser.add_argument("--steps", type=int, default=None, help="only the first N steps")
    args = parser.parse_args()
    config = load_config(args.config)
    for method, stance in (("multiple-shooting", "monitored"), ("multiple-shooting", "tracking"),
                           ("plain-shooting", "monitored")):
        spec = replace(walk_spec(config, method), stance=stance)
        if args.steps:
            spec.plans = spec.plans[: args.steps]
        warm = replace(spec, plans=spec.plans[:1])
        t0 = time.perf_counter()
        simulate_walk(warm)                      # builds every Function and solver once
        build = time.perf_counter() - t0
        walk = simulate_walk(spec)
        print(f"{method + ' ' + stance:28s} build {build:6.2f} s | {len(walk.steps)} steps, {walk.duration:5.2f} s walked "
              f"in {walk.wall_s:6.2f} s | real-time factor {walk.duration / walk.wall_s:5.2f} "
              f"(paper 0.32)")


if __name__ == "__main__":
    main()
