"""Test support, not part of klaw_ocp: ``python tests/_sweep_faults_main.py sweep ...`` is
``klaw-ocp sweep ...`` with chosen walks made to misbehave, for tests/test_sweep_faults.py.

``KLAW_TEST_SWEEP_FAULTS`` maps a walk.speed to what its walk does instead of walking, e.g.
``4.5=kill,4=after-kill,5=stall``:

- ``kill``: its worker process kills itself with SIGKILL, as the out-of-memory killer would
  (after writing its pid to ``$KLAW_TEST_SWEEP_DIR/killed-<pid>``);
- ``after-kill``: waits until a worker has been killed (its process gone), then walks: so that
  this walk is running while another worker dies;
- ``stall``: sleeps for two minutes (a long walk the sweep is stopped in the middle of).

``KLAW_TEST_SWEEP_WRITE_FAIL=N``: appending the N-th row to sweep.csv fails with ENOSPC.

The walk function is replaced in this module, which a spawned worker process imports as its
``__mp_main__`` (and a dask worker receives by value): the package itself has no such hook.
"""
import errno
import os
import signal
import sys
import time
from pathlib import Path

import klaw_ocp.sweep as sweep
from klaw_ocp.result_files.atomic import naming

#: how long ``after-kill`` waits for a worker to die before walking anyway, s
WAIT_S = 30.0


def _faults() -> dict[float, str]:
    text = os.environ.get("KLAW_TEST_SWEEP_FAULTS", "")
    return {float(k): v for k, v in (item.split("=") for item in text.split(",") if item)}


def _gone(pid: int) -> bool:
    try:
        state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return True
    return state in ("Z", "X")


def run_walk(mapping, method):
    import klaw_ocp.sweep as module      # the unchanged walk: this module may be imported twice
    real = getattr(module, "_unfaulted_run_walk", module.run_walk)
    fault = _faults().get(float(mapping["walk"]["speed"]))
    folder = Path(os.environ.get("KLAW_TEST_SWEEP_DIR", "."))
    if fault == "kill":
        (folder / f"killed-{os.getpid()}").write_text("")
        os.kill(os.getpid(), signal.SIGKILL)
    elif fault == "after-kill":
        end = time.monotonic() + WAIT_S
        while time.monotonic() < end and not any(_gone(int(p.name.split("-")[1])) for p in folder.glob("killed-*")):
            time.sleep(0.05)
    elif fault == "stall":
        time.sleep(120)
    return real(mapping, method)


_append = sweep.append_sweep_row
_appended = [0]


def append_sweep_row(path, row, varied_paths):
    _appended[0] += 1
    if _appended[0] == int(os.environ.get("KLAW_TEST_SWEEP_WRITE_FAIL", "0")):
        with naming(path):         # as the real write names its file
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    _append(path, row, varied_paths)


if not hasattr(sweep, "_unfaulted_run_walk"):
    sweep._unfaulted_run_walk = sweep.run_walk
    sweep.run_walk = run_walk
    sweep.append_sweep_row = append_sweep_row

if __name__ == "__main__":
    from klaw_ocp.cli import main
    sys.exit(main(sys.argv[1:]))
