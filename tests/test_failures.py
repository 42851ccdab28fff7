"""Failure loses nothing, and the same config gives the same files (issue #24, parts 2 and 4).

- A run writes each step as it completes (klaw_ocp.result_files.run_writer): dynamics.csv and events.csv
  grow, summary.json is rewritten; the final files are the bytes a one-shot render gives.
- A solver failure: one line with the step, the subphase, the residual and the real cause, exit 3,
  every completed step on disk; Ctrl-C: one line, exit 130, summary.json "interrupted", every
  completed step on disk (a real SIGINT to a real process).
- CasADi's warnings never reach the terminal; they go to summary.json.
- Determinism: two runs of a config, in each mode, give byte-identical files and summaries equal
  apart from their timing fields.
"""
import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

from klaw_ocp.cli import main
from klaw_ocp.errors import Interrupted, failure_cause

from _slow_cli import slow_cli_script

SRC = Path(__file__).resolve().parents[1] / "src"


def _steps_in_dynamics(folder: Path) -> list[int]:
    with open(folder / "dynamics.csv", newline="", encoding="utf-8") as handle:
        return sorted({int(row["step"]) for row in csv.DictReader(handle)})


def _config(tmp_path, name="walk", **sections):
    data = {"name": name, "body": {"height": 1.8, "mass": 80}, "walk": {"speed": 5.0, "steps": 2}}
    for key, value in sections.items():
        data[key] = {**data.get(key, {}), **value}
    path = tmp_path / f"{name}.yaml"
    path.write_text(yaml.safe_dump(data), encoding="utf-8")
    return path


#: the line a run prints before it compiles the solver kernels, the first time in a fresh
#: kernel cache (each test session has one: tests/conftest.py; tests/test_first_run.py)
COMPILING = "klaw-ocp: compiling the solver kernels"


def _lines(stderr: str) -> list:
    """The lines of ``stderr`` without the compile notice."""
    return [line for line in stderr.strip().splitlines() if not line.startswith(COMPILING)]


def _env():
    return {**os.environ, "PYTHONPATH": os.pathsep.join([str(SRC), os.environ.get("PYTHONPATH", "")]),
            "PYTHONWARNINGS": "ignore"}


# --------------------------------------------------------------------------- step by step

def test_each_step_is_on_disk_as_it_completes(tmp_path):
    """After step k, dynamics.csv holds the rows of steps 0..k, events.csv the events so far and
    summary.json (status running) every completed step; at the end the files are the bytes of
    a one-shot render of the same walk."""
    from klaw_ocp.config import load_config
    from klaw_ocp.result_files import render_walk
    from klaw_ocp.result_files.run_writer import RunWriter
    from klaw_ocp.walk import simulate_walk, walk_spec

    config = load_config(_config(tmp_path, walk={"steps": 3, "start_from_rest": True}))
    writer = RunWriter(tmp_path / "o", "resolved: true\n")
    seen = []

    def on_step(walk):
        writer.step(walk)
        summary = json.loads((tmp_path / "o" / "summary.json").read_text())
        assert summary["status"] == "running" and summary["steps_completed"] == len(walk.steps)
        assert [s["index"] for s in summary["steps"]] == list(range(len(walk.steps)))
        assert _steps_in_dynamics(tmp_path / "o") == list(range(len(walk.steps)))
        events = (tmp_path / "o" / "events.csv").read_text().splitlines()
        assert events[0] == "time,side,event" and len(events) - 1 == len(summary["events"])
        seen.append(len(walk.steps))

    walk = simulate_walk(walk_spec(config), on_step=on_step)
    assert seen == [1, 2, 3]
    writer.finish(walk)
    whole = render_walk(walk)          # at the walk's own fps, as the writer
    for name in ("dynamics", "summary", "events", "angles", "bvh", "mot"):
        filename, data = whole[name]
        assert (tmp_path / "o" / filename).read_bytes() == data, filename


def test_an_append_cut_short_is_overwritten(tmp_path, short_config):
    from klaw_ocp.config import load_config
    from klaw_ocp.result_files import render_walk
    from klaw_ocp.result_files.run_writer import RunWriter
    from klaw_ocp.walk import simulate_walk, walk_spec

    writer = RunWriter(tmp_path / "o")
    cut = []

    def on_step(walk):
        writer.step(walk)
        if not cut:   # half a row after the first step, as if Ctrl-C had cut its append
            with open(tmp_path / "o" / "dynamics.csv", "a") as handle:
                handle.write("0.123,1,swi")
            cut.append(True)
    walk = simulate_walk(walk_spec(load_config(short_config)), on_step=on_step)
    writer.finish(walk)
    assert (tmp_path / "o" / "dynamics.csv").read_bytes() == render_walk(walk)["dynamics"][1]


# ------------------------------------------------------------------------------- failures

@pytest.mark.parametrize("kwargs, words", [
    ({"residual": float("nan"), "message": "residual nan", "iterations": 3, "path_min": 1.0, "nlp": "rootfinder",
      "finite": False}, ["NaN or inf"]),
    ({"residual": 1e-3, "message": "Maximum_Iterations_Exceeded", "iterations": 500, "path_min": 0.0, "nlp": "ipopt"},
     ["iteration limit", "IPOPT", "500"]),
    ({"residual": 1e-3, "message": "Restoration_Failed", "iterations": 20, "path_min": 0.0, "nlp": "ipopt"},
     ["IPOPT: Restoration_Failed"]),
    ({"residual": 1e-6, "message": "residual 1e-06", "iterations": 7, "path_min": 0.0, "nlp": "rootfinder",
      "max_iterations": 7}, ["iteration limit", "7 Newton iterations"]),
    ({"residual": 1e-12, "message": "path constraint violated by 0.004", "iterations": 4, "path_min": -0.004,
      "nlp": "rootfinder", "max_iterations": 50}, ["path constraint violated by 0.004"]),
    ({"residual": 0.2, "message": "residual 0.2, implausible motion (a root far from any walk)", "iterations": 9,
      "path_min": 0.1, "nlp": "bisection-secant", "max_iterations": 60}, ["implausible motion"]),
    ({"residual": 0.2, "message": "residual 0.2", "iterations": 9, "path_min": 0.1, "nlp": "bisection-secant",
      "max_iterations": 60}, ["final conditions not met", "0.2"]),
    ({"residual": 0.2, "message": "no periodic start found"}, ["no periodic start found"]),
])
def test_the_cause_of_a_failure_is_named(kwargs, words):
    cause = failure_cause(**kwargs)
    assert all(w in cause for w in words), cause


@pytest.mark.parametrize("method, stance, cause", [
    ("multiple-shooting", "monitored", "iteration limit: 1 Newton iterations"),
    ("multiple-shooting", "tracking", "iteration limit: IPOPT stopped"),
])
def test_a_real_solver_failure_exits_3_with_one_line_and_nothing_else(method, stance, cause, tmp_path):
    """The solvers given one iteration (below what a config may ask: solver.max_iterations >= 3)
    fail the first stance: one line on stderr (no CasADi, no IPOPT), nothing on stdout, exit 3,
    and summary.json says why."""
    config = _config(tmp_path, solver={"method": method, "stance": stance})
    out = tmp_path / "o"
    one_iteration = ("import sys, klaw_ocp.walk as walk\n"
                     "make = walk.make_solver\n"
                     "walk.make_solver = lambda method, **kw: make(method, **{**kw, 'max_iterations': 1})\n"
                     "from klaw_ocp.cli import main\n"
                     "sys.exit(main(sys.argv[1:]))\n")
    r = subprocess.run([sys.executable, "-c", one_iteration, "run", str(config), "--out", str(out), "--quiet"],
                       capture_output=True, text=True, env=_env(), timeout=600)
    assert r.returncode == 3, r.stderr
    assert r.stdout == ""
    lines = _lines(r.stderr)
    assert len(lines) == 1, r.stderr
    assert lines[0].startswith("klaw-ocp: error: step 0, subphase 'stance': did not converge (residual ")
    assert cause in lines[0] and f"written to {out}" in lines[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps_completed"] == 0
    assert summary["failure"]["subphase"] == "stance" and cause in summary["failure"]["cause"]
    assert summary["failure"]["message"]                          # the solver's own words


def test_a_forced_failure_keeps_every_completed_step(tmp_path, capsys, fail_at_step):
    config = _config(tmp_path, walk={"steps": 4})
    fail_at_step(2, "swing3", 0.07)
    out = tmp_path / "o"
    assert main(["run", str(config), "--out", str(out), "--quiet", "--no-animation"]) == 3
    err = _lines(capsys.readouterr().err)
    assert len(err) == 1 and "step 2" in err[0] and "'swing3'" in err[0] and "0.07" in err[0]
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "failed" and summary["steps_completed"] == 2
    assert summary["failure"] == {"step": 2, "subphase": "swing3", "residual": 0.07, "cause": "forced for the test",
                                  "message": "forced for the test", "iterations": None, "path_min": None, "nlp": ""}
    assert _steps_in_dynamics(out) == [0, 1]
    assert (out / "angles.csv").is_file() and (out / "walk.bvh").is_file() and (out / "plots" / "legs.png").is_file()


# ------------------------------------------------------------------------------------ Ctrl-C

#: A walk of many slowed-down steps in a process of its own, with Python's own Ctrl-C handler
#: (a shell's background job would ignore SIGINT).
SLOW_RUN = slow_cli_script(0.5)


def _wait_for_steps(folder_glob, parent: Path, steps: int, process, timeout: float = 300.0) -> Path:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        assert process.poll() is None, process.communicate()
        for folder in parent.glob(folder_glob):
            try:
                if json.loads((folder / "summary.json").read_text())["steps_completed"] >= steps:
                    return folder
            except (OSError, ValueError, KeyError):
                pass
        time.sleep(0.05)
    raise AssertionError(f"no step on disk after {timeout} s")


def test_ctrl_c_exits_130_and_keeps_every_completed_step(tmp_path):
    config = _config(tmp_path, walk={"steps": 40})
    out = tmp_path / "o"
    out.mkdir()
    (out / "summary.json").write_text('{"steps": [], "body": {}}')       # an earlier run of ours
    earlier = (out / "summary.json").read_bytes()
    script = tmp_path / "slow_run.py"
    script.write_text(SLOW_RUN)
    process = subprocess.Popen([sys.executable, str(script), "run", str(config), "--out", str(out), "--quiet"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env())
    try:
        partial = _wait_for_steps("o.partial-*", tmp_path, 1, process)
        process.send_signal(signal.SIGINT)
        stdout, stderr = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == 130, stderr
    lines = _lines(stderr)
    assert len(lines) == 1 and lines[0].startswith("klaw-ocp: interrupted (Ctrl-C); "), stderr
    assert f"kept in {partial}" in lines[0] and "Traceback" not in stderr and stdout == ""
    assert (out / "summary.json").read_bytes() == earlier and sorted(p.name for p in out.iterdir()) == ["summary.json"]
    summary = json.loads((partial / "summary.json").read_text())
    k = summary["steps_completed"]
    assert summary["status"] == "interrupted" and 1 <= k < 40 and len(summary["steps"]) == k
    assert _steps_in_dynamics(partial) == list(range(k))
    assert (partial / "angles.csv").is_file() and not (partial / "plots").exists()


@pytest.fixture
def python_default_sigint():
    """Python's own Ctrl-C handler for the test: a suite started in the background (a shell job,
    ``nohup``, some CI runners) inherits SIGINT ignored, and Python then installs no handler, so
    a Ctrl-C sent to the process itself would be lost whatever the code does. The handler the
    suite started with is restored."""
    before = signal.signal(signal.SIGINT, signal.default_int_handler)
    yield
    signal.signal(signal.SIGINT, before)


def test_ctrl_c_waits_for_the_end_of_the_step(short_config, python_default_sigint):
    """CasADi turns a KeyboardInterrupt raised inside IPOPT into a failed solve: a walk takes the
    first Ctrl-C as a request and stops between steps (klaw_ocp.console.DeferredInterrupt)."""
    from klaw_ocp.walk import simulate_walk

    finished = []

    def press_ctrl_c(walk):
        if len(walk.steps) == 1:
            os.kill(os.getpid(), signal.SIGINT)     # delivered here, acted on before the next step
            time.sleep(0.05)                        # an immediate KeyboardInterrupt would stop here
            finished.append(len(walk.steps))
    with pytest.raises(Interrupted) as caught:
        simulate_walk(str(short_config), on_step=press_ctrl_c)
    walk = caught.value.partial
    assert finished == [1] and walk.status == "interrupted" and len(walk.steps) == 1
    assert signal.getsignal(signal.SIGINT) is signal.default_int_handler        # restored


# ---------------------------------------------------------------------- CasADi's own words

def test_casadis_warnings_go_to_the_summary_not_the_terminal(capfd):
    import casadi as ca
    from klaw_ocp.console import CasadiMessages

    x = ca.SX.sym("x")
    solver = ca.nlpsol("sqrt_of_negative", "ipopt", {"x": x, "f": ca.sqrt(x)},
                       {"ipopt.print_level": 0, "print_time": False, "ipopt.sb": "yes", "error_on_fail": False})
    with CasadiMessages() as messages:
        solver(x0=-1.0)                              # CasADi warns: NaN detected
        print("a line of our own", file=sys.stderr)
    captured = capfd.readouterr()
    assert "CasADi" not in captured.err and "a line of our own" in captured.err
    assert messages.messages and all(m.startswith("WARNING(") for m in messages.messages)
    assert "NaN detected" in messages.messages[0] and len(set(messages.messages)) == len(messages.messages)


def test_a_walk_keeps_casadis_warnings_in_its_summary(short_config, tmp_path, monkeypatch, capfd):
    from klaw_ocp.control.step import StepController
    original = StepController.solve_step

    def warning_step(self, plan, inp, k, at_rest=False):
        if k == 0:
            sys.stderr.write("CasADi - 2030-01-01 00:00:00 WARNING(\"a warning\") [file.cpp:1]\n")
        return original(self, plan, inp, k, at_rest)
    monkeypatch.setattr(StepController, "solve_step", warning_step)
    out = tmp_path / "o"
    assert main(["run", str(short_config), "--out", str(out), "--quiet", "--no-plots", "--no-animation"]) == 0
    assert "CasADi" not in capfd.readouterr().err
    assert json.loads((out / "summary.json").read_text())["solver_messages"] == ['WARNING("a warning") [file.cpp:1]']


# ------------------------------------------------------------------------------- determinism

TIMING = ("wall_s", "compile_s", "real_time_factor")
SUBPHASE_TIMING = ("wall_s", "build_s")


def _without_timings(summary: dict) -> dict:
    summary = {k: v for k, v in summary.items() if k not in TIMING}
    summary["steps"] = [dict(step, subphases=[{k: v for k, v in sub.items() if k not in SUBPHASE_TIMING}
                                              for sub in step["subphases"]]) for step in summary["steps"]]
    return summary


@pytest.mark.parametrize("method", ["multiple-shooting", "plain-shooting"])
def test_the_same_config_gives_the_same_files(method, tmp_path, capsys):
    config = _config(tmp_path, walk={"steps": 3, "start_from_rest": True})
    outs = [tmp_path / "a", tmp_path / "b"]
    for out in outs:
        assert main(["run", str(config), "--out", str(out), "--quiet", "--no-plots", "--no-animation",
                     "--method", method]) == 0
    a, b = outs
    for name in ("dynamics.csv", "events.csv", "angles.csv", "walk.bvh", "walk.mot", "config.resolved.yaml",
                 ".klaw-ocp"):
        assert (a / name).read_bytes() == (b / name).read_bytes(), name
    first, second = (json.loads((out / "summary.json").read_text()) for out in outs)
    assert first["wall_s"] != second["wall_s"]           # the timings do differ: they are left out
    assert _without_timings(first) == _without_timings(second)
    assert first["steps_completed"] == 3 and first["method"] == method
