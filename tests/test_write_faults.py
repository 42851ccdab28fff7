"""Results that cannot be written (issue #37, item 2): a full disk, a folder removed while the run
writes. Each ends in one line naming the path and the cause, exit 74, no traceback; the folder
that is kept never says "ok" for files it lacks; earlier results stay untouched.

The full disk is simulated in this process: every file the package writes goes through
``open`` in result_files.atomic and result_files.run_writer, and ``os.write`` in run_writer (the
step-by-step appends); a :class:`FullDisk` meters them and, from a named write on (the n-th write
of a file), refuses every write as a full disk does (OSError ENOSPC, naming no file). The disk
fills at a file, not at a byte count: summary.json, rewritten after every step, holds solve times
whose text length differs from run to run (``0.0123`` or ``0.012345678901234567``), so a byte
count taken from one run falls a file early or late in the next. Only the order of the writes is
taken from a recorded run, and it is the same in every run of the same walk.
"""
import builtins
import errno
import json
import os
import pickle
import shutil
import subprocess
import sys

import pytest

from klaw_ocp.cli import main
from klaw_ocp.commands import EXIT_WRITE_FAILED
from klaw_ocp.errors import os_error_text
from klaw_ocp.result_files import atomic, run_writer
from klaw_ocp.result_files.atomic import atomic_write_bytes

from _slow_cli import slow_cli_script
from test_failures import _config, _env, _lines, _wait_for_steps


def _file_name(path) -> str:
    """The result file a write goes to: ``path``'s name without its temporary's prefix and
    suffix (``.summary.json.k2x9a.tmp`` is summary.json; the marker's ``.klaw-ocp.k2x9a.tmp``
    is klaw-ocp)."""
    name = os.path.basename(str(path))
    if name.endswith(".tmp"):
        name = name[:-len(".tmp")].lstrip(".").rsplit(".", 1)[0]
    return name


class FullDisk:
    """A disk that fills at the ``nth`` write of the file ``name`` (``fills_at``; ``name`` may be
    a suffix: ".png" for any plot): that write and every later one raise ENOSPC, naming no file.
    ``freed``: the space the refused file's temporary held, given back when it is removed (a later
    write of up to that many bytes fits). ``writes``: each write's file name; ``refused``: the
    name of the write the disk filled at (None if it never filled)."""

    def __init__(self, fills_at: tuple[str, int] | None = None, freed: int = 0):
        self.fills_at, self.freed = fills_at, freed
        self.writes: list[str] = []
        self.room = float("inf")         # the bytes the disk still takes
        self.refused = None

    def take(self, n: int, path) -> None:
        name = _file_name(path)
        self.writes.append(name)
        if self.fills_at is not None and self.refused is None:
            target, nth = self.fills_at
            if sum(1 for written in self.writes if written.endswith(target)) == nth and name.endswith(target):
                self.room, self.refused = 0, name
        if n > self.room:
            self.room, self.freed = self.room + self.freed, 0
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC))
        self.room -= n


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


def _install(meter: FullDisk, monkeypatch) -> FullDisk:
    def metered_open(file, mode="r", *args, **kwargs):
        handle = builtins.open(file, mode, *args, **kwargs)
        return _Metered(handle, meter, file) if any(c in mode for c in "wa+") else handle
    for module in (atomic, run_writer):
        monkeypatch.setattr(module, "open", metered_open, raising=False)
    monkeypatch.setattr(run_writer, "os", _OsWithDisk(meter))
    return meter


@pytest.fixture
def disk(monkeypatch):
    def install(fills_at: tuple[str, int], freed: int = 0) -> FullDisk:
        return _install(FullDisk(fills_at, freed), monkeypatch)
    return install


def _run(config, out, *flags) -> int:
    return main(["run", str(config), "--out", str(out), "--quiet", "--no-animation", *flags])


@pytest.fixture(scope="module")
def four_steps(tmp_path_factory):
    return _config(tmp_path_factory.mktemp("config"), name="four", walk={"steps": 4})


@pytest.fixture(scope="module")
def writes(four_steps, tmp_path_factory):
    """The file of each write of a run with plots, in order (on a disk that never fills)."""
    patch = pytest.MonkeyPatch()
    try:
        meter = _install(FullDisk(), patch)
        assert _run(four_steps, tmp_path_factory.mktemp("layout") / "out") == 0
    finally:
        patch.undo()
    return meter.writes


#: the phases of a run a full disk can stop: the write the disk fills at (its file, which write
#: of it; -1 the last)
PHASES = {"the first step": ("dynamics.csv", 2), "a later step": ("dynamics.csv", 3),
          "the body files": ("walk.bvh", 1), "the plots": (".png", 1), "the final summary": ("summary.json", -1)}


@pytest.mark.parametrize("phase", list(PHASES))
def test_a_full_disk_is_one_line_exit_74_and_never_an_ok_summary(phase, writes, four_steps, disk, tmp_path,
                                                                  capsys):
    name, nth = PHASES[phase]
    if nth < 0:
        nth += 1 + sum(1 for written in writes if written.endswith(name))
    out = tmp_path / "out"
    out.mkdir()
    (out / "summary.json").write_text('{"steps": [], "body": {}}')       # an earlier run of ours
    earlier = (out / "summary.json").read_bytes()
    meter = disk((name, nth))
    code = _run(four_steps, out)
    err = _lines(capsys.readouterr().err)
    assert code == EXIT_WRITE_FAILED, err
    assert meter.refused is not None and meter.refused.endswith(name), (meter.refused, phase)
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: could not write "), err
    assert "No space left on device" in err[0] and "Traceback" not in err[0]
    kept = next(tmp_path.glob("out.partial-*"))
    assert f"kept in {kept} (the earlier results in {out} are untouched)" in err[0]
    named = err[0].split("could not write ")[1].split(": No space")[0]
    assert named.startswith(str(kept) + os.sep) and named.endswith(name), (named, phase)   # the file, as named now
    assert sorted(p.name for p in out.iterdir()) == ["summary.json"] and (out / "summary.json").read_bytes() == earlier
    # no summary (the disk filled before the first), one still "running", or "incomplete" with why
    summary = json.loads((kept / "summary.json").read_text()) if (kept / "summary.json").exists() else {}
    assert summary.get("status", "running") in ("running", "incomplete"), phase
    if summary.get("status") == "incomplete":
        assert summary["message"].startswith("could not write ") and "No space left on device" in summary["message"]
    assert not list(kept.rglob(".*.tmp"))               # no temporary left


def test_a_first_run_that_fills_the_disk_is_kept_in_place(four_steps, disk, tmp_path, capsys):
    out = tmp_path / "out"
    disk(("walk.bvh", 1), freed=10 ** 7)      # the half-written walk.bvh is removed
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
SLOW_RUN = slow_cli_script(0.3)


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
    assert lines[0].startswith(f"klaw-ocp: error: could not write {partial}{os.sep}")
    assert "No such file or directory" in lines[0] and lines[0].endswith("nothing written")
    assert not partial.exists() and not out.exists()          # nothing made again


def test_compare_on_a_full_disk_is_one_line_exit_74(short_config, disk, tmp_path, capsys):
    out = tmp_path / "cmp"
    meter = disk(("summary.json", 1))      # full in the first run's first step
    assert main(["compare", str(short_config), "--out", str(out), "--quiet"]) == EXIT_WRITE_FAILED
    err = _lines(capsys.readouterr().err)
    assert len(err) == 1 and err[0].startswith("klaw-ocp: error: could not write "), err
    assert "No space left on device" in err[0] and f"written to {out}" in err[0]
    assert all(json.loads(p.read_text())["status"] != "ok" for p in out.rglob("summary.json"))
    assert meter.refused == "summary.json"
