"""Benchmark: the playground's step, solved with its body frames and ready to send (#38, "Speed").

    python benchmarks/bench_serve.py [--steps 200] [--json]

1. The natural walk (5 km/h, 1.8 m, 80 kg, multiple shooting), ``--steps`` steps after five warm-up
   steps: for each, the time from asking for it to its message ready to send, as the server does
   it (:meth:`klaw_ocp.stepwise.StepwiseWalk.next_step`: the next step's stance half solved and this
   step's body frames on their window, then :func:`klaw_ocp.serve.protocol.step_text`, the message's
   JSON), split into those parts; then what the server does after sending it, while the page shows
   the step before (the rest of the next step: its swings and its rows of dynamics.csv,
   :meth:`~klaw_ocp.stepwise.StepwiseWalk.finish_ahead`, and its strips' JSON,
   :func:`~klaw_ocp.serve.protocol.strips_text`), and the step's whole work (the sum). p50 and p99
   of each.
2. How far ahead the next step is ready, at speeds across the envelope (0.5 to 9 km/h at eq. 1's
   natural step, in both solver modes): the step's duration over the time from asking for the next
   step to its message (a step is asked for as the one before begins, at the latest 0.25 s before
   it ends: the ratio says how many times over that time would have made it), and over the whole
   work of that step (its swings and rows too, which the server solves after sending). The
   smallest over the steps.

3. Memory: the process's resident size after one page's walk (warm: solvers built, kernels loaded),
   then after 20 more pages that each walked 10 steps and closed, through the ASGI test client:
   what sessions leave behind once they end.

The machine's load average is printed beside: the machine is shared, and a loaded one stretches
every number. So is how much slower than docs/performance.md's reference machine it runs this work
(the natural walk's median stance solve, :mod:`reference_machine`), with the ask's p50 and p99
scaled by that: an estimate for the reference machine, not a measurement. Timings are measured
here and in docs/performance.md, never asserted in tests.
"""
from __future__ import annotations

import argparse
import json
import os
import time

import numpy as np

from klaw_ocp.config import ExperimentConfig
from klaw_ocp.serve.protocol import step_text, strips_text
from klaw_ocp.solvers.thread_safety import solving
from klaw_ocp.step_body import step_frames
from klaw_ocp.stepwise import ReadyStep, StepwiseWalk
from reference_machine import REFERENCE_STANCE_SOLVE_MS, slower_than_reference

SPEEDS_KMH = (0.5, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0)


def config(speed: float, method: str = "multiple-shooting") -> ExperimentConfig:
    return ExperimentConfig.from_mapping({"name": "bench", "body": {"height": 1.8, "mass": 80.0},
                                          "walk": {"speed": speed, "steps": 1}, "solver": {"method": method}})


def timed_step(live: StepwiseWalk, strips: dict) -> dict:
    """One step made ready as StepwiseWalk.next_step makes it, each part timed (s): the next step's
    stance half, this step's frames and its message (its strips' JSON from ``strips``, written
    before); then, after it is sent, the rest of the next step (its swings and its rows of
    dynamics.csv: StepwiseWalk.finish_ahead, as the server calls it while the page shows the step
    before) and its strips' JSON, into ``strips``."""
    k = live._shown                                # noqa: SLF001 - the parts of next_step, timed
    t0 = time.perf_counter()
    with solving():
        live._ahead = live._loop.begin_next()      # noqa: SLF001
    t1 = time.perf_counter()
    frames = step_frames(live.walk, k, live.spec.fps, live._ahead, live._prepared)     # noqa: SLF001
    live._prepared = None                          # noqa: SLF001
    t2 = time.perf_counter()
    live._shown += 1                               # noqa: SLF001
    ready = ReadyStep(k, live.walk.steps[k], live._rows.pop(k), frames, t2 - t0, False)     # noqa: SLF001
    step_text(ready, live.attributes, {"step": live.last_planned.index}, strips.pop(k, None))
    t3 = time.perf_counter()
    result = live.finish_ahead()
    if result is not None:                         # its strips' text, as the server writes it then
        strips[result.index] = strips_text(live.rows(result.index))
    t4 = time.perf_counter()
    return {"stance": t1 - t0, "frames": t2 - t1, "message": t3 - t2, "ready": t3 - t0,
            "rest": t4 - t3, "work": t4 - t0, "t_step": live.walk.steps[k].plan.timings.t_step}


PARTS = {"ready": "ready to send (asked -> message)", "stance": "  the next step's stance half",
         "frames": "  this step's frames", "message": "  its message (JSON)",
         "rest": "after sending: next step's rest", "work": "the whole step's work"}


def warm(live: StepwiseWalk, steps: int) -> dict:
    """Hand out ``steps`` steps, solve the rest of the next one; returns the walk's strips' JSON by
    step (the server's ``LiveSession.strips``), for :func:`timed_step`."""
    for _ in range(steps):
        live.next_step()
    result = live.finish_ahead()
    return {result.index: strips_text(live.rows(result.index))}


def natural(steps: int) -> dict:
    live = StepwiseWalk(config(5.0))
    strips = warm(live, 5)
    rows = [timed_step(live, strips) for _ in range(steps)]
    out = {}
    for part in PARTS:
        ms = np.array([r[part] for r in rows]) * 1000
        out[part] = {"p50_ms": float(np.percentile(ms, 50)), "p99_ms": float(np.percentile(ms, 99))}
    # the machine: the walk's median stance solve, as bench_walk measures it
    out["stance_solve_ms"] = 1000 * float(np.median([s.subphase("stance").wall_s for s in live.walk.steps]))
    return out


def ahead(speed: float, method: str, steps: int = 12) -> tuple[float, float]:
    """The smallest ratios of a step's duration to the time from asking for the next step to its
    message (what the page waits for), and to the whole work of that step (with its swings and
    rows, solved after sending)."""
    live = StepwiseWalk(config(speed, method))
    strips = warm(live, 1)
    rows = [timed_step(live, strips) for _ in range(steps)]
    return min(r["t_step"] / r["ready"] for r in rows), min(r["t_step"] / r["work"] for r in rows)


def rss_mb() -> float:
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE") / 2**20


def memory(pages: int = 20, steps: int = 10) -> dict:
    import gc

    from starlette.testclient import TestClient

    from klaw_ocp.serve.app import create_app

    def walk_a_page(client):
        with client.websocket_connect("/walk", headers={"origin": "http://testserver"}) as ws:
            sent = 0
            while sent < steps:
                message = json.loads(ws.receive_text())
                if message["type"] == "step":
                    sent += 1
                    ws.send_text(json.dumps({"type": "need", "step": message["index"] + 1}))

    with TestClient(create_app(config(5.0))) as client:
        walk_a_page(client)
        gc.collect()
        idle = rss_mb()
        for _ in range(pages):
            walk_a_page(client)
        gc.collect()
        time.sleep(0.5)
        return {"idle_mb": idle, "after_mb": rss_mb(), "pages": pages, "live_walks_left": len(client.app.state.walks)}


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--steps", type=int, default=200)
    parser.add_argument("--json", action="store_true")
    args = parser.parse_args()
    load = os.getloadavg()[0]
    result = {"load_average": load, "natural": natural(args.steps), "ahead": {}}
    for part in PARTS:
        values = result["natural"][part]
        print(f"natural walk, {PARTS[part]:34s}: p50 {values['p50_ms']:6.2f} ms  p99 {values['p99_ms']:6.2f} ms")
    solve = result["natural"]["stance_solve_ms"]
    result["slower_than_reference"] = slower = slower_than_reference(solve)
    ready = result["natural"]["ready"]
    print(f"this machine's median stance solve is {solve:.2f} ms, {slower:.2f}x the reference machine's "
          f"{REFERENCE_STANCE_SOLVE_MS} ms (docs/performance.md); scaled by that (an estimate, not measured): "
          f"asked -> message ready p50 ~{ready['p50_ms'] / slower:.1f} ms, p99 ~{ready['p99_ms'] / slower:.1f} ms")
    for method in ("multiple-shooting", "plain-shooting"):
        ratios = {speed: ahead(speed, method) for speed in SPEEDS_KMH}
        result["ahead"][method] = ratios
        print(f"ready ahead ({method}, ask -> ready / whole work): "
              + ", ".join(f"{v:g} km/h {r:.0f}x/{w:.0f}x" for v, (r, w) in ratios.items())
              + f"; smallest {min(r for r, _ in ratios.values()):.1f}x / {min(w for _, w in ratios.values()):.1f}x")
    result["memory"] = m = memory()
    print(f"memory: {m['idle_mb']:.0f} MB after one page, {m['after_mb']:.0f} MB after {m['pages']} more "
          f"(walks left alive: {m['live_walks_left']})")
    print(f"load average {load:.2f} on {os.cpu_count()} cores (a shared machine: a loaded one stretches every number)")
    if args.json:
        print(json.dumps(result))


if __name__ == "__main__":
    main()
