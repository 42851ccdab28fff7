"""Every signal a user or a system sends ends a run cleanly (issue #37, item 5): real processes,
real signals.

Ctrl-C from a terminal goes to every process of the job: the test starts the run in a process
group of its own and sends SIGINT to the group (the drawing workers and their forkserver get it
too); SIGTERM goes to the run's process alone (``kill``, a container stop) or to the group
(systemd, a batch scheduler). Each ends in one line from the main process, no traceback, exit 130
for Ctrl-C and 143 for SIGTERM, the completed steps kept under the documented name with status
"interrupted", earlier results untouched, and no process of the group left.

The moments are made reliable by the run's own code slowed down in the process under test (a
step, the solver's construction, the periodic start, each plot in the workers: through a module
the workers' forkserver preloads), each saying when it has begun by a file.
"""
import glob
import json
import os
import signal
import subprocess
import sys
import textwrap
import time

import pytest

from klaw_ocp.commands import EXIT_INTERRUPTED, EXIT_TERMINATED

from test_failures import _config, _env, _lines

#: the run, its chosen moment slowed down (MOMENT), READY written when the moment has begun
SCRIPT = textwrap.dedent("""
    if __name__ == "__main__":    # the workers import this file as their main module: nothing to run there
        import os, signal, sys, time
        signal.signal(signal.SIGINT, signal.default_int_handler)   # a background job inherits it ignored
        def ready():
            open(os.environ["READY"], "w").close()
        moment = os.environ["MOMENT"]
        if moment == "steps":
            from klaw_ocp.control.step import StepController
            original = StepController.solve_step
            def slow(self, *args, **kwargs):
                result = original(self, *args, **kwargs)
                if args[2] == 1:
                    ready()
                time.sleep(0.3)
                return result
            StepController.solve_step = slow
        elif moment in ("solver", "periodic_start"):
            import klaw_ocp.step_loop as step_loop
            import klaw_ocp.walk as walk
            owner, name = (walk, "StepController") if moment == "solver" else (step_loop, "periodic_start")
            original = getattr(owner, name)
            def held(*args, **kwargs):
                ready()
                time.sleep(1.0)
                return original(*args, **kwargs)
            setattr(owner, name, held)
        elif moment == "plots":
            from klaw_ocp.figures import render_pool
            render_pool.PRELOAD.append("slow_draw")
        from klaw_ocp.cli import main
        sys.exit(main(sys.argv[1:]))
""")

#: preloaded by the workers' forkserver: every plot waits long before it is drawn
SLOW_DRAW = textwrap.dedent("""
    import os, time
    from klaw_ocp.figures import render_pool
    original = render_pool._draw
    def slow(run, task, gif_path):
        open(os.environ["READY"], "w").close()
        time.sleep(60)
        return original(run, task, gif_path)
    render_pool._draw = slow
""")


def _group(pgid: int) -> list[str]:
    """The processes (alive or zombie) of process group ``pgid``."""
    members = []
    for stat in glob.glob("/proc/[0-9]*/stat"):
        try:
            with open(stat) as handle:
                fields = handle.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        if int(fields[2]) == pgid:
            members.append(stat.split("/")[2])
    return members


def _none_left(pgid: int) -> list[str]:
    """The group's processes once they have had time to end (none, if the run ended them)."""
    deadline = time.monotonic() + 30
    while _group(pgid) and time.monotonic() < deadline:
        time.sleep(0.1)
    return _group(pgid)


def _run_and_signal(tmp_path, moment: str, signum, to_group: bool, steps: int = 2, flags=()):
    config = _config(tmp_path, walk={"steps": steps})
    out = tmp_path / "o"
    out.mkdir()
    (out / "summary.json").write_text('{"steps": [], "body": {}}')       # an earlier run of ours
    script, ready = tmp_path / "run.py", tmp_path / "ready"
    script.write_text(SCRIPT)
    (tmp_path / "slow_draw.py").write_text(SLOW_DRAW)
    env = _env()
    env.update(MOMENT=moment, READY=str(ready), PYTHONPATH=os.pathsep.join([str(tmp_path), env["PYTHONPATH"]]))
    process = subprocess.Popen([sys.executable, str(script), "run", str(config), "--out", str(out), "--quiet",
                                *flags], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env,
                               start_new_session=True)
    try:
        deadline = time.monotonic() + 300
        while not ready.exists():
            assert process.poll() is None and time.monotonic() < deadline, process.communicate()
            time.sleep(0.02)
        (os.killpg if to_group else os.kill)(process.pid, signum)
        stdout, stderr = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            os.killpg(process.pid, signal.SIGKILL)
    left = _none_left(process.pid)
    return process.returncode, stdout, stderr, out, left


CASES = {  # moment: (signal, to the group, steps, flags)
    "Ctrl-C after step 1": ("steps", signal.SIGINT, True, 20, ("--no-plots", "--no-animation")),
    "SIGTERM after step 1": ("steps", signal.SIGTERM, False, 20, ("--no-plots", "--no-animation")),
    "Ctrl-C while the solver is built": ("solver", signal.SIGINT, True, 2, ("--no-plots", "--no-animation")),
    "Ctrl-C in the periodic start": ("periodic_start", signal.SIGINT, True, 2, ("--no-plots", "--no-animation")),
    "SIGTERM in the periodic start": ("periodic_start", signal.SIGTERM, False, 2, ("--no-plots", "--no-animation")),
    "Ctrl-C during the plots": ("plots", signal.SIGINT, True, 2, ("--no-animation",)),
    "SIGTERM to the job during the plots": ("plots", signal.SIGTERM, True, 2, ("--no-animation",)),
    "SIGTERM to the run during the plots and walk.gif": ("plots", signal.SIGTERM, False, 2, ()),
}


@pytest.mark.parametrize("case", list(CASES))
def test_a_signal_ends_the_run_in_one_line_keeping_what_was_done(case, tmp_path):
    moment, signum, to_group, steps, flags = CASES[case]
    code, stdout, stderr, out, left = _run_and_signal(tmp_path, moment, signum, to_group, steps, flags)
    words = "interrupted (Ctrl-C)" if signum == signal.SIGINT else "terminated (SIGTERM)"
    assert code == (EXIT_INTERRUPTED if signum == signal.SIGINT else EXIT_TERMINATED), stderr
    lines = _lines(stderr)
    assert len(lines) == 1 and lines[0].startswith(f"klaw-ocp: {words}; "), stderr
    assert "Traceback" not in stderr and stdout == ""
    assert left == [], f"processes left: {left}"
    # the earlier results untouched, the new ones beside them under the documented name
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"]
    partial = sorted(out.parent.glob("o.partial-*"))
    assert len(partial) == 1 and f"kept in {partial[0]} (the earlier results in {out} are untouched)" in lines[0]
    summary = json.loads((partial[0] / "summary.json").read_text())
    assert summary["status"] == "interrupted" and summary["message"].startswith(words)
    done = summary["steps_completed"]
    assert f"{done} completed step(s)" in lines[0]
    assert done >= (1 if moment == "steps" else 0) and (moment != "plots" or done == steps)
    assert not (partial[0] / "walk.gif").exists() and not list(partial[0].rglob(".*.tmp"))
    assert not list(partial[0].glob(".walk.gif.*"))
