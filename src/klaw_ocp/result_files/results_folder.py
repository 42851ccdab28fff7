"""Results folders that never mix two runs and that a failing run never destroys (issue #24).

Every command that writes a results folder (``run``, ``compare``, ``sweep``, ``reproduce``)
writes it through a :class:`StagedFolder`:

1. Before anything is solved, ``--out`` is checked (:func:`inspect_folder`): a missing or empty
   folder, or one that klaw-ocp wrote for the same command, is accepted; a non-empty folder
   klaw-ocp did not write (or wrote for another command, or holds files it did not write) is
   refused with one line and exit 2, unless ``--force``.
2. The new results are written into a sibling folder ``<out>.partial-<YYYYmmdd-HHMMSS>``
   (``-2``, ``-3``, ... when two start in the same second).
3. A command that ends well calls :meth:`StagedFolder.commit`: the marker is written, the earlier
   folder is renamed aside (``.<name>.old-<stamp>-<pid>``), the new one renamed into its place and
   the earlier one deleted: no file of the earlier run survives.
4. A command that fails or is interrupted calls :meth:`StagedFolder.keep`: the earlier folder
   stays as it was and the new one is kept beside it under its ``.partial-`` name, which the
   command's one-line message gives; with no earlier folder (none, or an empty one) the partial
   results take its place instead; an empty staging folder is removed.

With ``--force`` a foreign folder is written into instead of being replaced: klaw-ocp's files
replace those of the same name (and those its marker lists from an earlier forced run), every
other file stays, and the folder stays foreign (the next run into it needs ``--force`` again).

The marker, ``.klaw-ocp``, is a small JSON file: ``written_by``, ``version``, ``command`` and
``files`` (every file of the folder klaw-ocp wrote, relative, sorted). A folder without it is
still recognised as klaw-ocp's (written before the marker existed) when it holds the command's
key file (``summary.json``, ``comparison.csv``, ``sweep.csv``, ``numbers.json``) and only files
the command writes. What each command writes is the registry's (:mod:`.registry`).
"""
from __future__ import annotations

import contextlib
import fnmatch
import itertools
import json
import os
import shutil
import time
from pathlib import Path

from ..errors import KlawError
from ..stop_signals import Deferred
from .registry import COMMAND_FOLDERS, KEY_FILES, MARKER

#: Files that desktops and the atomic writes leave anywhere; they never make a folder foreign.
JUNK = (".DS_Store", "Thumbs.db", "desktop.ini", ".*.tmp")
#: A folder with more entries than this is not a results folder (and is not listed further).
MAX_ENTRIES = 2000


class OutputFolderError(KlawError):
    """``--out`` names a folder that klaw-ocp will not write into."""


def _matches(rel: str, patterns) -> bool:
    parts = rel.split("/")
    return any(len(p) == len(parts) and all(fnmatch.fnmatchcase(a, b) for a, b in zip(parts, p))
               for p in (q.split("/") for q in patterns))


def _is_prefix(rel: str, patterns) -> bool:
    """A folder on the way to some pattern (``runs/x`` for ``runs/*/summary.json``)."""
    parts = rel.split("/")
    return any(len(p) > len(parts) and all(fnmatch.fnmatchcase(a, b) for a, b in zip(parts, p))
               for p in (q.split("/") for q in patterns))


def _entries(folder: Path):
    """Every file and folder under ``folder``, relative with ``/``, folders first (symlinks are
    listed, never followed)."""
    for root, dirs, files in os.walk(folder):
        base = Path(root).relative_to(folder)
        for name in sorted(dirs):
            yield (base / name).as_posix(), True
        for name in sorted(files):
            yield (base / name).as_posix(), False


def read_marker(folder: Path) -> dict | None:
    """The marker of ``folder`` as a dict, or None (missing, unreadable, not ours)."""
    try:
        data = json.loads((Path(folder) / MARKER).read_text(encoding="utf-8"))
    except (OSError, UnicodeDecodeError, ValueError):
        return None
    if not isinstance(data, dict) or data.get("written_by") != "klaw-ocp" or not isinstance(data.get("files"), list):
        return None
    return data


def inspect_folder(folder, command: str) -> tuple[str, str]:
    """What ``folder`` is to ``command``: ``("missing", "")``, ``("empty", "")``, ``("ours", "")``
    or ``("foreign", why)``, ``why`` a few words for the one-line refusal."""
    folder = Path(folder)
    if not folder.exists() and not folder.is_symlink():
        return "missing", ""
    if not folder.is_dir():
        return "foreign", "it is not a folder"
    marker = read_marker(folder)
    if marker is not None and marker.get("command") != command:
        return "foreign", f"it holds the results of klaw-ocp {marker.get('command')}"
    allowed = COMMAND_FOLDERS[command]
    listed = {str(f) for f in marker["files"]} if marker is not None else set()
    listed_dirs = {f.rsplit("/", i)[0] for f in listed for i in range(1, f.count("/") + 1)}
    if marker is None and (folder / MARKER).exists():
        return "foreign", f"its {MARKER} is not klaw-ocp's"
    strangers, n = [], 0
    try:
        for rel, is_dir in _entries(folder):
            n += 1
            if n > MAX_ENTRIES:
                return "foreign", f"it has more than {MAX_ENTRIES} files"
            name = rel.rsplit("/", 1)[-1]
            ok = (rel == MARKER or rel in listed or (is_dir and rel in listed_dirs) or _matches(rel, allowed)
                  or (is_dir and _is_prefix(rel, allowed)) or any(fnmatch.fnmatchcase(name, j) for j in JUNK))
            if not ok:
                strangers.append(rel)
                if len(strangers) > 3:
                    break
    except OSError as exc:
        return "foreign", f"it cannot be listed ({type(exc).__name__})"
    if n == 0:
        return "empty", ""
    if strangers:
        shown = ", ".join(strangers[:3]) + (" and more" if len(strangers) > 3 else "")
        return "foreign", f"it has {shown}"
    if marker is None and not (folder / KEY_FILES[command]).is_file():
        return "foreign", f"it has no {KEY_FILES[command]} and no {MARKER} marker"
    return "ours", ""


def _files(folder: Path) -> list[str]:
    return sorted(rel for rel, is_dir in _entries(folder) if not is_dir and rel != MARKER)


def mark_folder(folder, command: str) -> None:
    """Write the marker of a folder klaw-ocp ``command`` wrote: every file in it is listed."""
    from .. import __version__
    from .atomic import atomic_write_text
    marker = {"written_by": "klaw-ocp", "version": __version__, "command": command, "files": _files(Path(folder))}
    atomic_write_text(Path(folder) / MARKER, json.dumps(marker, indent=2) + "\n")


class StagedFolder:
    """The results folder ``out`` of ``command``, checked now, written beside it, swapped in at
    the end (see the module docstring). A refusal names ``--out``, the option of every command
    that writes one."""

    def __init__(self, out, command: str, force: bool = False):
        if command not in COMMAND_FOLDERS:
            raise ValueError(f"unknown command {command!r}")
        self.out, self.command, self.force = Path(out), command, force
        # a symlinked --out: the folder it points to is the one replaced
        self.target = Path(os.path.realpath(self.out))
        if not self.target.name:
            raise OutputFolderError(f"--out: got {str(out)!r}, allowed a folder below the file system's root")
        self.state, why = inspect_folder(self.target, command)
        if self.state == "foreign" and not self.target.is_dir():
            raise OutputFolderError(f"--out: got {str(out)!r}, a file, allowed a folder")
        if self.state == "foreign" and not force:
            raise OutputFolderError(f"--out: got {str(out)!r}, a non-empty folder that klaw-ocp {command} "
                                    f"did not write ({why}); choose another folder, or add --force to write "
                                    f"into it (its other files are kept)")
        self.path: Path | None = None
        #: where :meth:`keep` left the results (None: nowhere, nothing written)
        self.kept: Path | None = None

    # -- writing ---------------------------------------------------------------------------------
    def open(self) -> Path:
        """Create the staging folder beside ``out`` and return it."""
        parent = self.target.parent
        stamp = time.strftime("%Y%m%d-%H%M%S")
        try:
            parent.mkdir(parents=True, exist_ok=True)
            for n in itertools.count(1):
                path = parent / (f"{self.target.name}.partial-{stamp}" + (f"-{n}" if n > 1 else ""))
                try:
                    path.mkdir()
                except FileExistsError:
                    continue
                self.path = path
                return path
        except OSError as exc:
            raise OutputFolderError(f"--out: got {str(self.out)!r}, where no folder can be created beside it "
                                    f"({exc.strerror or type(exc).__name__}: {exc.filename}), allowed a "
                                    f"writable place") from None
        raise AssertionError("unreachable")

    def _write_marker(self) -> None:
        mark_folder(self.path, self.command)

    def commit(self) -> Path:
        """The command ended well: the new folder replaces the earlier one whole (with
        ``--force`` on a foreign folder: its files are moved into it). Returns ``out``."""
        self._write_marker()
        # Ctrl-C and SIGTERM wait: two folders are never left half swapped (and the command, done,
        # ends as done: its results are whole)
        with Deferred(second_raises=False):
            state, why = inspect_folder(self.target, self.command)
            if state == "foreign" and not self.force:     # it changed while the command ran
                kept, self.path = self.shown(self.path), None
                raise OutputFolderError(f"{self.out}: became a folder klaw-ocp {self.command} did not write "
                                        f"while the command ran ({why}); its results are in {kept}")
            if state == "foreign":
                self._merge()
            elif state == "missing":
                os.rename(self.path, self.target)
            elif state == "empty":
                os.rmdir(self.target)
                os.rename(self.path, self.target)
            else:
                stamp = time.strftime("%Y%m%d-%H%M%S")
                old = self.target.parent / f".{self.target.name}.old-{stamp}-{os.getpid()}"
                os.rename(self.target, old)
                try:
                    os.rename(self.path, self.target)
                except BaseException:
                    os.rename(old, self.target)
                    raise
                shutil.rmtree(old, ignore_errors=True)
        self.path = None
        return self.out

    def _merge(self) -> None:
        earlier = read_marker(self.target)
        if earlier is not None and earlier.get("command") != self.command:
            earlier = None
        new = _files(self.path)
        for rel in new + [MARKER]:
            dest = self.target / rel
            dest.parent.mkdir(parents=True, exist_ok=True)
            os.replace(self.path / rel, dest)
        stale = set(str(f) for f in (earlier or {}).get("files", [])) - set(new)
        for rel in sorted(stale):
            with contextlib.suppress(OSError):
                (self.target / rel).unlink()
        shutil.rmtree(self.path, ignore_errors=True)

    def keep(self) -> Path | None:
        """The command failed or was interrupted: keep what it wrote without touching the earlier
        folder. Returns where it is: ``out`` when there was no earlier folder (the partial
        results took its place), else the ``.partial-`` folder beside it; None when nothing had
        been written (the empty staging folder is removed)."""
        self.kept = self._keep()
        return self.kept

    def _keep(self) -> Path | None:
        if self.path is None or not self.path.is_dir():
            self.path = None
            return None
        # it runs when writing has just failed (a full disk, a folder removed): each step that
        # fails leaves the results where they are, under their .partial- name; a stop signal
        # waits (the command is ending: it says where its results are)
        with Deferred(second_raises=False):
            try:
                if not any(self.path.iterdir()):
                    self.path.rmdir()
                    self.path = None
                    return None
            except OSError:
                pass
            with contextlib.suppress(OSError):     # without its marker the folder is still ours (its files)
                self._write_marker()
            state, _ = inspect_folder(self.target, self.command)
            if state in ("missing", "empty"):
                try:
                    if state == "empty":
                        os.rmdir(self.target)
                    os.rename(self.path, self.target)
                    self.path = None
                    return self.out
                except OSError:
                    pass
        kept, self.path = self.shown(self.path), None
        return kept if kept.is_dir() else None

    def shown(self, path: Path) -> Path:
        """``path`` (beside ``out``) as the user would name it: beside ``out`` as typed."""
        if Path(os.path.realpath(self.out.parent)) == path.parent:
            return self.out.parent / path.name
        return path


def kept_phrase(kept: Path | None, staged: StagedFolder) -> str:
    """How a one-line message says where a failed or interrupted command's results are."""
    if kept is None:
        return f"nothing written; {staged.out} is as it was" if staged.state == "ours" else "nothing written"
    if Path(kept) == staged.out:
        return f"written to {staged.out}"
    where = (f"the earlier results in {staged.out} are untouched" if staged.state == "ours"
             else f"{staged.out} is untouched")
    return f"kept in {kept} ({where})"
