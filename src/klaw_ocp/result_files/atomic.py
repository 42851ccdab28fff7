"""Atomic writes: a reader never sees a half-written result file (a temporary file in the same
folder, then a rename), and the file gets the user's normal mode. Every writer of the package,
and the figures, write through here; this module imports nothing of the package."""
from __future__ import annotations

import os
import tempfile
from contextlib import contextmanager, suppress
from pathlib import Path


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


@contextmanager
def naming(path):
    """An OSError raised in the block names ``path`` if it names no file: a write, a flush or a
    close that fails (a full disk) does not say which file, and the user's one line should."""
    try:
        yield
    except OSError as exc:
        # only an error from the system (an errno): one raised with a message alone would print
        # as "[Errno None] None: <file>", its message lost
        if exc.filename is None and exc.errno is not None:
            exc.filename = os.fspath(path)
        raise


@contextmanager
def atomic_path(path: Path, suffix: str = ".tmp"):
    """A temporary path in ``path``'s folder to write the file into; when the block ends, the file
    gets the user's normal mode (mkstemp makes it 0600) and is renamed to ``path``, so that a reader
    never sees a half-written file; if the block raises, the temporary is removed. An OSError names
    ``path`` (not the temporary)."""
    path = Path(path)
    tmp = None
    try:
        path.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=suffix)
        os.close(fd)
        yield Path(tmp)
        os.chmod(tmp, 0o666 & ~_umask())
        os.replace(tmp, path)
    except BaseException as exc:
        if tmp is not None:
            with suppress(OSError):          # a folder removed meanwhile has no temporary left
                os.unlink(tmp)
        if isinstance(exc, OSError) and exc.errno is not None and (exc.filename is None or os.fspath(exc.filename) == tmp):
            exc.filename, exc.filename2 = os.fspath(path), None
        raise


def atomic_write_bytes(path: Path, data: bytes, durable: bool = True) -> None:
    """Write ``data`` to ``path`` atomically (:func:`atomic_path`). ``durable``: flushed to the
    disk before the rename (fsync, a few ms); without it the file is as safe against a crash of
    the process, not against one of the machine (the per-step rewrites of a run,
    :mod:`klaw_ocp.result_files.run_writer`)."""
    with atomic_path(path) as tmp, open(tmp, "wb") as handle:
        handle.write(data)
        handle.flush()
        if durable:
            os.fsync(handle.fileno())


def atomic_write_text(path: Path, text: str, durable: bool = True) -> None:
    """:func:`atomic_write_bytes` of UTF-8 text (newlines written as given)."""
    atomic_write_bytes(path, text.encode("utf-8"), durable)


def write_rendered(files: dict, out_dir) -> dict:
    """Write rendered files (name -> (file name, bytes), :func:`klaw_ocp.result_files.render_walk`)
    atomically into ``out_dir``; returns name -> path."""
    out = Path(out_dir)
    paths = {}
    for name, (filename, data) in files.items():
        paths[name] = out / filename
        atomic_write_bytes(paths[name], data)
    return paths
