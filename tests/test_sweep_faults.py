"""A sweep survives what happens to its processes (issue #37 items 2, 3, 5; docs/sweep.md):
a worker killed with SIGKILL loses only the walk it was running; Ctrl-C and SIGTERM stop the
sweep with one line, the finished walks kept and no worker left; a file that cannot be written
is one line and exit 74. Real processes: the CLI runs in a subprocess
(tests/_sweep_faults_main.py makes chosen walks kill their worker or stall), every wait has a
timeout, and no test measures time."""
import csv
import errno
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import yaml

import klaw_ocp
from klaw_ocp import sweep
from klaw_ocp.cli import main
from klaw_ocp.sweep_pool import death_cause

MAIN = Path(__file__).resolve().parent / "_sweep_faults_main.py"
SHORT = {"name": "short", "body": {"height": 1.8, "mass": 80},
         "walk": {"speed": 5.0, "steps": 2}, "solver": {"method": "plain-shooting"}}
#: the longest a sweep subprocess may take, s: a hang fails the test instead of the suite
TIMEOUT = 240


@pytest.fixture
def config(tmp_path):
    path = tmp_path / "short.yaml"
    path.write_text(yaml.safe_dump(SHORT))
    return path


def _start(tmp_path, config, speeds: str, faults: str, *options, write_fail: int = 0, session=False):
    env = {**os.environ, "KLAW_TEST_SWEEP_FAULTS": faults, "KLAW_TEST_SWEEP_DIR": str(tmp_path),
           "KLAW_TEST_SWEEP_WRITE_FAIL": str(write_fail),
           "PYTHONPATH": os.pathsep.join([str(Path(klaw_ocp.__file__).parents[1]),
                                          os.environ.get("PYTHONPATH", "")])}
    argv = [sys.executable, str(MAIN), "sweep", str(config), "--vary", f"walk.speed={speeds}",
            "--out", str(tmp_path / "out"), "--quiet", *options]
    return subprocess.Popen(argv, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                            start_new_session=session)


def _finish(proc) -> tuple[int, str, list[str]]:
    """Exit code, stdout and the lines on stderr (the one-time compile notice left out)."""
    try:
        out, err = proc.communicate(timeout=TIMEOUT)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL) if _own_group(proc) else proc.kill()
        proc.communicate()
        pytest.fail("the sweep hung")
    lines = [line for line in err.splitlines() if line and "compiling the solver kernels" not in line]
    return proc.returncode, out, lines


def _own_group(proc) -> bool:
    try:
        return os.getpgid(proc.pid) == proc.pid
    except ProcessLookupError:
        return False


def _rows(path) -> list[dict]:
    with open(path, newline="") as handle:
        return list(csv.DictReader(handle))


def _children(pid: int) -> set[int]:
    out = set()
    for stat in Path("/proc").glob("[0-9]*/stat"):
        try:
            fields = stat.read_text().rsplit(")", 1)[1].split()
        except (OSError, IndexError):
            continue
        if int(fields[1]) == pid:
            out.add(int(stat.parent.name))
    return out


def _alive(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return False
    return state not in ("Z", "X")


def _wait_for(condition, what: str, proc=None):
    end = time.monotonic() + TIMEOUT
    while not condition():
        if proc is not None and proc.poll() is not None:
            pytest.fail(f"the sweep ended before {what}: {proc.communicate()}")
        if time.monotonic() > end:
            pytest.fail(f"waited too long for {what}")
        time.sleep(0.05)


def _first_row_written(tmp_path) -> bool:
    for path in [*tmp_path.glob("out.partial-*/sweep.csv"), tmp_path / "out" / "sweep.csv"]:
        try:
            if path.read_text().count("\n") >= 2:
                return True
        except OSError:
            pass
    return False


def _assert_no_process_left(pids: set[int]) -> None:
    _wait_for(lambda: not any(_alive(p) for p in pids), "the worker processes to end")


# ----------------------------------------------------------------------------- a worker killed

def test_a_killed_worker_loses_only_its_walk(config, tmp_path):
    """4.5 km/h kills its worker with SIGKILL while 4 km/h is running in the other one: 4.5 is
    lost with the signal, 4 finishes, 5 runs in a new worker; exit 3, as for a failed walk."""
    proc = _start(tmp_path, config, "4,4.5,5", "4=after-kill,4.5=kill", "--workers", "2")
    code, out, err = _finish(proc)
    assert len(list(tmp_path.glob("killed-*"))) == 1, "the walk killed its worker once"
    assert code == 3, (out, err)
    rows = _rows(tmp_path / "out" / "sweep.csv")
    assert [(r["walk.speed"], r["status"]) for r in rows] == [("4", "ok"), ("4.5", "lost"), ("5", "ok")]
    assert rows[1]["message"] == "worker process died (signal 9: SIGKILL), possibly out of memory"
    assert rows[0]["steps"] == rows[2]["steps"] == "2" and rows[1]["steps"] == ""
    assert out.startswith("3 walks: 2 ok, 0 failed, 0 error, 1 lost; wrote")
    assert len(err) == 1 and "walk.speed=4.5 (plain-shooting): worker process died (signal 9: SIGKILL)" in err[0]


def test_a_walk_killed_on_a_dask_cluster_is_lost_the_others_finish(config, tmp_path, monkeypatch):
    """dask's nanny restarts the dead worker and the scheduler retries the task; the second
    death (allowed-failures 1) makes it a KilledWorker: that walk is lost, the others ok."""
    distributed = pytest.importorskip("distributed")
    import dask
    # the cluster's workers are this process's children: they read the faults from here
    monkeypatch.setenv("KLAW_TEST_SWEEP_FAULTS", "4.5=kill")
    monkeypatch.setenv("KLAW_TEST_SWEEP_DIR", str(tmp_path))
    # one task per worker thread, so that a death blames only the walk running there
    settings = {"distributed.scheduler.allowed-failures": 1, "distributed.scheduler.worker-saturation": 1.0}
    with dask.config.set(settings), distributed.LocalCluster(
            n_workers=2, processes=True, threads_per_worker=1, dashboard_address=None) as cluster:
        proc = _start(tmp_path, config, "4,4.5,5", "4.5=kill", "--scheduler", cluster.scheduler_address)
        code, out, err = _finish(proc)
    assert code == 3, (out, err)
    assert len(list(tmp_path.glob("killed-*"))) == 2, "tried twice"
    rows = _rows(tmp_path / "out" / "sweep.csv")
    assert [(r["walk.speed"], r["status"]) for r in rows] == [("4", "ok"), ("4.5", "lost"), ("5", "ok")]
    assert "worker process died 2 times running it (dask KilledWorker)" in rows[1]["message"]
    assert len(err) == 1 and "walk.speed=4.5" in err[0]


@pytest.mark.parametrize("exitcode, words", [
    (-9, "worker process died (signal 9: SIGKILL), possibly out of memory"),
    (-11, "worker process died (signal 11: SIGSEGV), a crash in native code"),
    (-15, "worker process died (signal 15: SIGTERM)"),
    (1, "worker process exited with code 1"),
])
def test_death_cause(exitcode, words):
    assert death_cause(exitcode) == words


# ---------------------------------------------------------------------------- Ctrl-C, SIGTERM

@pytest.mark.parametrize("signum, to_group, workers, code, line", [
    (signal.SIGINT, True, "2", 130, "klaw-ocp: interrupted (Ctrl-C); "),      # a terminal's Ctrl-C
    (signal.SIGTERM, False, "2", 143, "klaw-ocp: terminated (SIGTERM); "),    # kill PID
    (signal.SIGTERM, True, "2", 143, "klaw-ocp: terminated (SIGTERM); "),     # a service stopped
    (signal.SIGTERM, False, "1", 143, "klaw-ocp: terminated (SIGTERM); "),    # walks in its process
])
def test_a_signal_stops_the_sweep_keeping_the_finished_walks(config, tmp_path, signum, to_group, workers, code, line):
    """The walk at 5 km/h stalls, so the signal comes mid-sweep: one line, the exit code, the
    finished walks in sweep.csv (the stalled one and those not started are not written), and
    no worker process left."""
    speeds = "4,5,4.5,3.5" if workers == "2" else "4,5"
    proc = _start(tmp_path, config, speeds, "5=stall", "--workers", workers, session=True)
    _wait_for(lambda: _first_row_written(tmp_path), "the first walk", proc)
    children = _children(proc.pid)
    (os.killpg if to_group else os.kill)(proc.pid, signum)
    got, out, err = _finish(proc)
    assert got == code and out == "", err
    assert len(err) == 1 and err[0].startswith(line) and "finished walk(s) written to" in err[0], err
    rows = _rows(tmp_path / "out" / "sweep.csv")
    assert rows and all(r["status"] == "ok" for r in rows) and "5" not in [r["walk.speed"] for r in rows]
    assert err[0].split("; ")[1].startswith(f"{len(rows)} finished walk(s)")
    _assert_no_process_left(children)


def test_a_sweep_killed_leaves_no_worker_walking(config, tmp_path):
    """SIGKILL to the sweep's process (nothing can be said then): its workers notice within a
    second that their parent is gone and end, the stalled walk included."""
    proc = _start(tmp_path, config, "4,5,4.5", "5=stall", "--workers", "2", session=True)
    _wait_for(lambda: _first_row_written(tmp_path), "the first walk", proc)
    children = _children(proc.pid)
    assert children, "the sweep has worker processes"
    proc.kill()
    proc.communicate(timeout=TIMEOUT)
    _assert_no_process_left(children)


# ------------------------------------------------------------------------------- write errors

def test_a_row_that_cannot_be_written_stops_the_sweep_in_one_line(config, tmp_path):
    """The second row's line fails with ENOSPC while a walk is still running in a worker: one
    line naming sweep.csv and the cause, exit 74, the first row kept, no worker left."""
    proc = _start(tmp_path, config, "4,5,4.5,3.5", "5=stall", "--workers", "2", write_fail=2)
    _wait_for(lambda: _first_row_written(tmp_path), "the first walk", proc)
    children = _children(proc.pid)
    code, out, err = _finish(proc)
    assert code == 74 and out == "", err
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: could not write ")
    assert "sweep.csv: No space left on device; 1 finished walk(s) written to" in err[0]
    assert [r["walk.speed"] for r in _rows(tmp_path / "out" / "sweep.csv")] == ["4"]
    _assert_no_process_left(children)


def test_appending_a_row_names_the_file_when_the_disk_is_full(tmp_path, monkeypatch):
    path = tmp_path / "sweep.csv"
    row = {"walk.speed": 4, "method": "plain-shooting", "status": "ok"}
    sweep.append_sweep_row(path, row, ["walk.speed"])

    def full(fd):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(os, "fsync", full)
    with pytest.raises(OSError) as caught:
        sweep.append_sweep_row(path, row, ["walk.speed"])
    assert caught.value.filename == str(path) and caught.value.errno == errno.ENOSPC


def test_a_map_that_cannot_be_written_is_one_line(config, tmp_path, capsys, monkeypatch):
    """sweep.png fails (its fsync, on a full disk: an OSError that names no file): one line
    naming it, exit 74, sweep.csv kept."""
    def quick(mapping, method):
        return {**dict.fromkeys(sweep.RESULT_COLUMNS), "method": method, "status": "ok", "steps": 2, "wall_s": 0.1}

    fsync = os.fsync

    def full_for_the_map(fd):
        if ".sweep.png." in os.readlink(f"/proc/self/fd/{fd}"):      # atomic_path's temporary of the map
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        return fsync(fd)
    monkeypatch.setattr(sweep, "run_walk", quick)
    monkeypatch.setattr(os, "fsync", full_for_the_map)
    out = tmp_path / "out"
    argv = ["sweep", str(config), "--vary", "walk.speed=4,5", "--workers", "1", "--quiet", "--out", str(out)]
    assert main(argv) == 74
    captured = capsys.readouterr()
    err = captured.err.strip().splitlines()
    assert captured.out == "" and len(err) == 1 and "Traceback" not in captured.err
    assert err[0].startswith(f"klaw-ocp: error: could not write {out / 'sweep.png'}: No space left on device;")
    assert err[0].endswith(f"all 2 walks written to {out}")      # no earlier sweep: the folder took its place
    assert [r["walk.speed"] for r in _rows(out / "sweep.csv")] == ["4", "5"]


def test_a_stop_signal_a_walk_swallowed_stops_a_sweep_in_its_process(monkeypatch):
    """With --workers 1 a Ctrl-C or SIGTERM that never surfaced (CasADi's wrappers drop the
    KeyboardInterrupt) still stops the sweep after that walk, its row dropped; one recorded
    before the sweep began (an earlier walk in the same interpreter) does not."""
    from klaw_ocp.errors import Interrupted
    from klaw_ocp.stop_signals import Deferred

    def swallow_a_ctrl_c():
        with Deferred():              # recorded, never raised: as inside CasADi
            os.kill(os.getpid(), signal.SIGINT)
    walked = []

    def swallowing(mapping, method):
        walked.append(mapping["walk"]["speed"])
        if len(walked) == 2:
            swallow_a_ctrl_c()
        return {**dict.fromkeys(sweep.RESULT_COLUMNS), "method": method, "status": "ok"}
    monkeypatch.setattr(sweep, "run_walk", swallowing)
    swallow_a_ctrl_c()                # before the sweep
    with pytest.raises(Interrupted) as caught:
        sweep.run_sweep(SHORT, {"walk.speed": [4.0, 5.0, 6.0]}, workers=1)
    assert walked == [4.0, 5.0] and [row["walk.speed"] for row in caught.value.partial] == [4.0]
