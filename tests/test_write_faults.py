"""Results that cannot be written (issue #37, item 2): a full disk, a folder removed while the run
writes. Each ends in one line naming the path and the cause, exit 74, no traceback; the folder
that is kept never says "ok" for files it lacks; earlier results stay untouched.

The full disk is simulated in this process: every file the package writes goes through
``open`` in result_files.atomic and result_files.run_writer, and ``os.write`` in run_writer (the
step-by-step appends); a :class:`FullDisk` meters them and refuses, as a full disk does
(OSError ENOSPC, naming no file), the first write past its budget. A first run records where
each file's bytes start, so that the budgets fall in every phase of a run: its first step, a later
step, the body files, the plots, the final summary.
"""
import builtins
import errno
import json
import os
import pickle
import shutil
import subprocess
import sys
import textwrap

import pytest

from klaw_ocp.cli import main
from klaw_ocp.commands import EXIT_WRITE_FAILED
from klaw_ocp.errors import os_error_text
from klaw_ocp.result_files import atomic, run_writer
from klaw_ocp.result_files.atomic import atomic_write_bytes

from test_failures import _config, _env, _lines, _wait_for_steps


class FullDisk:
    """A disk of ``budget`` bytes: a write past it raises ENOSPC, naming no file. ``writes``:
    each write's file name and the bytes used before it."""

    def __init__(self, budget: float, freed: int = 0):
        self.budget, self.used, self.writes, self.freed = budget, 0, [], freed

    def take(self, n: int, name) -> None:
        name = os.path.basename(str(name)).split(".tmp")[0].lstrip(".")
        self.writes.append((name.rsplit(".", 1)[0] if name.count(".") > 1 else name, self.used))
        if self.used + n > self.budget:
            # ``freed``: the space the refused file's temporary held, given back when it is removed
            self.budget, self.freed = self.budget + self.freed, 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.used += n


class _Metered:
    def __init__(self, handle, disk: FullDisk, name):
        self._handle, self._disk, self._name = handle, disk, name

    def write(self, data):
        self._disk.take(len(data.encode("utf-8") if isinstance(data, str) else data), self._name)
        return self._handle.write(data)

    def __enter__(self):
        return self

    def __exit__(self, *exc):
        self._handle.close()

    def __getattr__(self, name):
        return getattr(self._handle, name)


class _OsWithDisk:
    """``os`` for run_writer, its ``write`` metered."""

    def __init__(self, disk: FullDisk):
        self._disk = disk

    def write(self, fd, data):
        self._disk.take(len(data), "dynamics.csv")
        return os.write(fd, data)

    def __getattr__(self, name):
        return getattr(os, name)


@pytest.fixture
def disk(monkeypatch):
    def install(budget: float, freed: int = 0) -> FullDisk:
        meter = FullDisk(budget, freed)

        def metered_open(file, mode="r", *args, **kwargs):
            handle = builtins.open(file, mode, *args, **kwargs)
            return _Metered(handle, meter, file) if any(c in mode for c in "wa+") else handle
        for module in (atomic, run_writer):
            monkeypatch.setattr(module, "open", metered_open, raising=False)
        monkeypatch.setattr(run_writer, "os", _OsWithDisk(meter))
        return meter
    return install


def _run(config, out, *flags) -> int:
    return main(["run", str(config), "--out", str(out), "--quiet", "--no-animation", *flags])


@pytest.fixture(scope="module")
def four_steps(tmp_path_factory):
    return _config(tmp_path_factory.mktemp("config"), name="four", walk={"steps": 4})


@pytest.fixture(scope="module")
def layout(four_steps, tmp_path_factory):
    """Each write of a run with plots: (file name, bytes used before it), and the bytes of the
    run (measured on an unlimited disk)."""
    import klaw_ocp.result_files.atomic as a
    import klaw_ocp.result_files.run_writer as w
    meter, patch = FullDisk(float("inf")), pytest.MonkeyPatch()

    def metered_open(file, mode="r", *args, **kwargs):
        handle = builtins.open(file, mode, *args, **kwargs)
        return _Metered(handle, meter, file) if any(c in mode for c in "wa+") else handle
    for module in (a, w):
        patch.setattr(module, "open", metered_open, raising=False)
    patch.setattr(w, "os", _OsWithDisk(meter))
    try:
        assert _run(four_steps, tmp_path_factory.mktemp("layout") / "out") == 0
    finally:
        patch.undo()
    return meter.writes, meter.used


def _before(writes, name: str, nth: int = 1) -> int:
    """The bytes used before the ``nth`` write of ``name`` (a suffix: ".png" for any plot)."""
    return [used for written, used in writes if written == name or written.endswith(name)][nth - 1]


#: the phases of a run a full disk can stop: the write that fails (its file, which write of it)
PHASES = {"the first step": ("dynamics.csv", 2), "a later step": ("dynamics.csv", 3),
          "the body files": ("walk.bvh", 1), "the plots": (".png", 1), "the final summary": ("summary.json", -1)}


@pytest.mark.parametrize("phase", list(PHASES))
def test_a_full_disk_is_one_line_exit_74_and_never_an_ok_summary(phase, layout, four_steps, disk, tmp_path,
                                                                  capsys):
    writes, _ = layout
    name, nth = PHASES[phase]
    budget = _before(writes, name, nth) if nth > 0 else [u for w, u in writes if w == name][nth]
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text('{"steps": [], "body": {}}')       # an earlier run of ours
    earlier = (out / "summary.json").read_bytes()
    disk(budget)
    code = _run(four_steps, out)
    err = _lines(capsys.readouterr().err)
    assert code == EXIT_WRITE_FAILED, err
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: writing the results failed: "), err
    assert "No space left on device" in err[0] and "Traceback" not in err[0]
    kept = next(tmp_path.glob("out.partial-*"))
    assert f"kept in {kept} (the earlier results in {out} are untouched)" in err[0]
    named = err[0].split("writing the results failed: ")[1].split(": No space")[0]
    assert named.startswith(str(kept) + os.sep)          # the file, as it is named now
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"] and (out / "summary.json").read_bytes() == earlier
    # no summary (the disk filled before the first), one still "running", or "incomplete" with why
    summary = json.loads((kept / "summary.json").read_text()) if (kept / "summary.json").exists() else {}
    assert summary.get("status", "running") in ("running", "incomplete"), phase
    if summary.get("status") == "incomplete":
        assert "No space left on device" in summary["message"]
    assert not list(kept.rglob(".*.tmp"))               # no temporary left


def test_a_first_run_that_fills_the_disk_is_kept_in_place(layout, four_steps, disk, tmp_path, capsys):
    writes, _ = layout
    out = tmp_path / "out"
    disk(_before(writes, "walk.bvh"), freed=10 ** 7)      # the half-written walk.bvh is removed
    assert _run(four_steps, out) == EXIT_WRITE_FAILED
    err = _lines(capsys.readouterr().err)
    assert len(err) == 1 and f"written to {out}" in err[0] and f"{out}{os.sep}walk.bvh: No space" in err[0], err
    assert json.loads((out / "summary.json").read_text())["status"] == "incomplete"
    assert not (out / "walk.bvh").exists() and not list(tmp_path.glob("out.partial-*"))


def test_a_failed_write_names_the_file_not_its_temporary(tmp_path, monkeypatch):
    def full(*args, **kwargs):
        raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
    monkeypatch.setattr(atomic.os, "replace", full)
    with pytest.raises(OSError) as caught:
        atomic_write_bytes(tmp_path / "walk.bvh", b"x")
    assert os_error_text(caught.value) == f"{tmp_path / 'walk.bvh'}: No space left on device"
    assert list(tmp_path.iterdir()) == []
    # a worker's error (walk.gif is written in one) crosses the process boundary with its path
    assert pickle.loads(pickle.dumps(caught.value)).filename == str(tmp_path / "walk.bvh")


#: a run whose steps are slowed down and whose staging folder the test removes after step 1
SLOW_RUN = textwrap.dedent("""
    import sys, time
    from klaw_ocp.control.step import StepController
    original = StepController.solve_step
    def slow(self, *args, **kwargs):
        result = original(self, *args, **kwargs)
        time.sleep(0.3)
        return result
    StepController.solve_step = slow
    from klaw_ocp.cli import main
    sys.exit(main(sys.argv[1:]))
""")


def test_a_folder_removed_while_the_run_writes_is_one_line_and_exit_74(tmp_path):
    """A real process whose results folder is removed under it (root writes anywhere, so a
    folder made read-only would not stop it; a removed one stops everyone)."""
    config = _config(tmp_path, walk={"steps": 20})
    out = tmp_path / "o"
    script = tmp_path / "slow_run.py"
    script.write_text(SLOW_RUN)
    process = subprocess.Popen([sys.executable, str(script), "run", str(config), "--out", str(out), "--quiet",
                                "--no-plots", "--no-animation"],
                               stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=_env())
    try:
        partial = _wait_for_steps("o.partial-*", tmp_path, 1, process)
        shutil.rmtree(partial)
        stdout, stderr = process.communicate(timeout=300)
    finally:
        if process.poll() is None:
            process.kill()
    assert process.returncode == EXIT_WRITE_FAILED, stderr
    lines = _lines(stderr)
    assert len(lines) == 1 and "Traceback" not in stderr and stdout == "", stderr
    assert lines[0].startswith(f"klaw-ocp: error: writing the results failed: {partial}{os.sep}")
    assert "No such file or directory" in lines[0] and lines[0].endswith("nothing written")
    assert not partial.exists() and not out.exists()          # nothing made again


def test_compare_on_a_full_disk_is_one_line_exit_74(short_config, disk, tmp_path, capsys):
    out = tmp_path / "cmp"
    disk(30_000)            # the first run's folder, then full
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == EXIT_WRITE_FAILED
    err = _lines(capsys.readouterr().err)
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: writing the results failed: "), err
    assert "No space left on device" in err[0] and f"written to {out}" in err[0]
    assert all(json.loads(p.read_text())["status"] != "ok" for p in out.rglob("summary.json"))
