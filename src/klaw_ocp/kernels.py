"""CasADi Functions compiled to C once per machine, cached on disk, called from numpy.

The solvers spend their time in a few SX Functions per subphase (the RK4 interval over the grid,
its per-interval Jacobians, the final conditions). CasADi's virtual machine evaluates them about
ten times slower than the same expressions compiled, and a CasADi call with numpy arguments
costs tens of microseconds of conversion. A :class:`KernelLibrary` therefore

1. looks for a shared library under a key that names the problem's structure (the subphase's
   serialised right-hand side, the grid size, the CasADi version, this generator's version, the
   compiler and its flags, the platform): a cache hit builds no CasADi expression at all;
2. otherwise builds the Functions, generates C with CasADi's ``CodeGenerator`` and compiles it
   with the system C compiler (``$CC``, else ``cc``/``gcc``), ``-O2``: against ``-O1`` a warm
   natural walk executes 5 % fewer instructions (475 M -> 452 M, callgrind; the kernels' own
   share ~12 % fewer), with the same numbers to the last bit, for about 1-2 s more compiling
   the first time on a machine; ``-O3`` gains nothing more;
3. calls the compiled functions through ``ctypes`` with preallocated work arrays (about 2 us a
   call), or, without a working compiler (or with ``KLAW_OCP_JIT=0``), the same Functions
   through CasADi: everything runs, only slower (:mod:`.kernel_calls`).

The cache folder is ``$KLAW_OCP_CACHE_DIR``, else ``$XDG_CACHE_HOME/klaw_ocp``, else
``~/.cache/klaw_ocp``. Several processes (sweep workers) may build the same library at once:
each compiles into its own temporary file and renames it into place, which is atomic, so a
reader sees either no library or a whole one. Beside each library its key and the SHA-256 of its
bytes are written (``.sha256``, flushed to disk and renamed into place before the library): a
library is verified against them before it is loaded, since loading a damaged one can kill the
process (a truncated file: SIGBUS when the loader touches the missing pages) or load another
kernel's code (a library copied over another: undefined symbols). One that does not match, or
does not load, is rebuilt, once, with a one-line note (a ``RuntimeWarning``,
:class:`KernelCacheNote`); if the rebuilt one fails too, CasADi evaluates the kernels.

Compiling takes seconds where everything else takes milliseconds, so it is announced and timed:
:func:`compile_notices` tells a listener (the command line) before compiling starts, and
:func:`compile_seconds` is the wall time spent compiling (a walk's ``compile_s``).

Arrays cross this boundary flat, in CasADi's column-major order: an (nx, N) matrix is a numpy
array of shape (N, nx) in C order. One kernel object serves every thread of the process: each
thread calls it with work arrays of its own (:mod:`.kernel_calls`), so walks in several threads
run their kernels at the same time (docs/limits.md, "Threads"). Libraries are loaded once, under
a lock per library; CasADi expressions are built and C generated one at a time for the process
(:mod:`klaw_ocp.casadi_builds`), while the compilers run in parallel (:func:`prefetch`).
"""
from __future__ import annotations

import ctypes
import hashlib
import os
import platform
import shutil
import subprocess
import sys
import tempfile
import threading
import time
import warnings
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Optional, Sequence

import casadi as ca

from .casadi_builds import BUILD_LOCK
from .kernel_calls import CasadiFunction, CompiledFunction

#: bump when the generated functions change in a way their key does not capture (the source of
#: the modules that build them is part of the key already, see :func:`source_key`)
GENERATOR_VERSION = "1"
FLAGS = ("-O2", "-fPIC", "-shared")
_DISABLED = ("0", "off", "false", "no")
_compiler_state: dict = {}
#: who is told that compiling starts (:func:`compile_notices`), and the compile clock: how many
#: libraries compile right now, since when, and the seconds of the finished bursts
_listeners: list = []
_clock = {"active": 0, "since": 0.0, "total": 0.0}
_clock_lock = threading.Lock()


@contextmanager
def compile_notices(listener: Callable[[Path], None]):
    """Within the block, ``listener(folder)`` is called (from the compiling thread) each time a
    library starts compiling while no other one is: before the pause, so that whoever runs the
    solvers can say why they pause. ``folder`` is the cache the library goes into. The solvers
    know nothing of who listens (the command line prints one line, docs/performance.md)."""
    with _clock_lock:
        _listeners.append(listener)
    try:
        yield
    finally:
        with _clock_lock:
            _listeners.remove(listener)


def compile_seconds() -> float:
    """Wall time this process has spent compiling kernels (building their CasADi Functions,
    generating C and running the compiler), finished compiles only. Libraries compiled at once
    (:func:`prefetch`) count once: this is time the caller waited, not CPU time."""
    with _clock_lock:
        return _clock["total"]


@contextmanager
def _compiling(folder: Path):
    """Time one library's compile on the clock, telling the listeners when a burst starts."""
    with _clock_lock:
        starts = _clock["active"] == 0
        _clock["active"] += 1
        listeners = list(_listeners) if starts else []
        if starts:
            _clock["since"] = time.perf_counter()
    try:
        for listener in listeners:
            try:
                listener(folder)
            except Exception:  # noqa: BLE001 - a notice that cannot be given (stderr closed)
                pass           # must not turn the compile into the slow CasADi fallback
        yield
    finally:
        with _clock_lock:
            _clock["active"] -= 1
            if _clock["active"] == 0:
                _clock["total"] += time.perf_counter() - _clock["since"]


def source_key(*modules) -> str:
    """A digest of the source files of the modules that build a library: editing the code that
    generates a kernel gives it a new key, so a stale compiled kernel is never loaded."""
    digest = hashlib.sha256()
    for module in (sys.modules[__name__], *modules):
        digest.update(Path(module.__file__).read_bytes())
    return digest.hexdigest()


def cache_dir() -> Path:
    """Where compiled kernels live (created on demand), one folder per CasADi version."""
    root = os.environ.get("KLAW_OCP_CACHE_DIR")
    if not root:
        base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
        root = os.path.join(base, "klaw_ocp")
    return Path(root) / f"casadi-{ca.__version__}"


def compiler() -> Optional[str]:
    """The C compiler to use, or None (JIT disabled, or no compiler found)."""
    if os.environ.get("KLAW_OCP_JIT", "1").strip().lower() in _DISABLED:
        return None
    if "path" not in _compiler_state:
        candidates = [os.environ["CC"]] if os.environ.get("CC") else ["cc", "gcc", "clang"]
        _compiler_state["path"] = next((shutil.which(c) for c in candidates if shutil.which(c)), None)
    return _compiler_state["path"]


def _compiler_identity(cc: str) -> str:
    """The compiler's version line: part of the key, so an upgraded compiler rebuilds."""
    if cc not in _compiler_state:
        try:
            out = subprocess.run([cc, "--version"], capture_output=True, text=True, timeout=30).stdout
            _compiler_state[cc] = out.splitlines()[0] if out else cc
        except (OSError, subprocess.SubprocessError):
            _compiler_state[cc] = cc
    return _compiler_state[cc]


class KernelCacheNote(RuntimeWarning):
    """A cached kernel library was damaged or would not load, and was rebuilt (one line)."""


def _file_digest(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _stamp_text(key: str, digest: str) -> str:
    return f"{key} {digest}\n"


def _write_synced(path: Path, data: bytes) -> None:
    """``data`` into ``path``, flushed to the disk before it is renamed into place."""
    tmp = path.with_name(f".{path.name}.{os.getpid()}.{threading.get_ident()}.tmp")
    with open(tmp, "wb") as f:
        f.write(data)
        f.flush()
        os.fsync(f.fileno())
    os.replace(tmp, path)


class KernelLibrary:
    """Named CasADi Functions built on first use, compiled and cached when a compiler works.

    ``build(compiling)`` returns the Functions named ``names``, in that order; it runs only when
    the library is not in the cache or no compiler is available (``compiling`` says which: the
    forms that compile well and those CasADi's virtual machine evaluates fastest differ). ``key_parts`` name
    everything the generated code depends on besides CasADi's version and the compiler; ``what``
    names the library's kernels in the notes about them.
    """

    def __init__(self, key_parts: Sequence, names: Sequence[str], build: Callable[[bool], list],
                 what: str = "solver kernel"):
        self._build, self._functions, self.names, self.what = build, None, tuple(names), what
        digest = hashlib.sha256()
        for part in (GENERATOR_VERSION, sys.platform, platform.machine(), *key_parts):
            digest.update(repr(part).encode() if not isinstance(part, (bytes, str)) else
                          part.encode() if isinstance(part, str) else part)
            digest.update(b"\0")
        self._digest = digest
        self._lock = threading.Lock()
        self.path: Optional[Path] = None
        self.compiled = False

    def _casadi_functions(self, compiling: bool = False) -> dict:
        with BUILD_LOCK:   # CasADi expressions and their C one at a time (klaw_ocp.casadi_builds)
            if self._functions is None:
                self._functions = {fn.name(): fn for fn in self._build(compiling)}
                if tuple(self._functions) != self.names:
                    raise ValueError(f"kernel library built {tuple(self._functions)}, expected {self.names}")
            return self._functions

    def library_path(self) -> Optional[Path]:
        """Where this library is cached with the current compiler (None: no compiler)."""
        cc = compiler()
        if cc is None:
            return None
        digest = self._digest.copy()
        digest.update(" ".join([_compiler_identity(cc), *FLAGS]).encode())
        return cache_dir() / f"{digest.hexdigest()[:32]}.so"

    def will_compile(self) -> bool:
        """Whether :meth:`load` would compile (a compiler, and no library in the cache yet)."""
        if hasattr(self, "_lib"):
            return False
        path = self.library_path()
        return path is not None and not path.exists()

    def _load(self) -> Optional[ctypes.CDLL]:
        path = self.library_path()
        if path is None:
            return None
        cc, folder = compiler(), path.parent
        if path.exists():
            problem = self._damage(path)
            if problem is None:
                try:
                    lib = ctypes.CDLL(str(path))
                    self.path = path
                    return lib
                except OSError as err:   # e.g. built on another machine sharing the folder
                    problem = f"does not load ({str(err).splitlines()[0] if str(err) else type(err).__name__})"
            warnings.warn(f"klaw_ocp: the cached {self.what} {path} {problem}; rebuilding it",
                          KernelCacheNote, stacklevel=3)
        try:
            with _compiling(folder):
                folder.mkdir(parents=True, exist_ok=True)
                self._compile(cc, folder, path)
            lib = ctypes.CDLL(str(path))
        except (OSError, subprocess.SubprocessError, RuntimeError) as err:
            self._functions = None   # built for compiling; CasADi evaluates another form faster
            warnings.warn(f"klaw_ocp: compiling {self.what}s failed ({err}); evaluating them "
                          f"with CasADi instead (slower). Set KLAW_OCP_JIT=0 to skip compiling.",
                          RuntimeWarning, stacklevel=3)
            return None
        self.path = path
        return lib

    def _stamp_path(self, path: Path) -> Path:
        return path.with_suffix(".sha256")

    def _damage(self, path: Path) -> Optional[str]:
        """Why the cached library at ``path`` must not be loaded, or None: its stamp (this key and
        the SHA-256 of its bytes) missing, for another key, or not its bytes'."""
        try:
            stamp = self._stamp_path(path).read_text(encoding="ascii").split()
            digest = _file_digest(path)
        except (OSError, UnicodeDecodeError) as err:
            return f"has no readable checksum ({type(err).__name__})"
        if len(stamp) != 2 or stamp[0] != path.stem:
            return "has a checksum of another kernel"
        if stamp[1] != digest:
            return "does not match its checksum (damaged or replaced)"
        return None

    def _compile(self, cc: str, folder: Path, path: Path) -> None:
        with tempfile.TemporaryDirectory(dir=folder, prefix=".build-") as tmp:
            source = Path(tmp) / "kernels.c"
            with BUILD_LOCK:
                generator = ca.CodeGenerator(source.name, {"with_header": False})
                for fn in self._casadi_functions(compiling=True).values():
                    generator.add(fn)
                generator.generate(tmp + os.sep)
            built = Path(tmp) / "kernels.so"
            result = subprocess.run([cc, *FLAGS, str(source), "-o", str(built), "-lm"],
                                    capture_output=True, text=True, timeout=900)
            if result.returncode != 0:
                raise RuntimeError(f"{cc} exited with {result.returncode}: {result.stderr.strip()[:300]}")
            os.chmod(built, 0o755)
            with open(built, "rb+") as f:   # on the disk before it is renamed into place
                os.fsync(f.fileno())
            # the stamp first: a reader that meets a new library finds its stamp (one that meets a
            # new stamp beside the old library sees a mismatch and rebuilds, which is only slower)
            _write_synced(self._stamp_path(path), _stamp_text(path.stem, _file_digest(built)).encode("ascii"))
            os.replace(built, path)   # atomic: concurrent builders each rename a whole library

    def load(self) -> Optional[ctypes.CDLL]:
        """Compile or load the library once (None: evaluate with CasADi)."""
        with self._lock:
            if not hasattr(self, "_lib"):
                self._lib = self._load()
                self.compiled = self._lib is not None
            return self._lib

    def functions(self) -> dict:
        """name -> callable on flat numpy arrays (compiled when possible; dense arrays only)."""
        lib = self.load()
        if lib is not None:
            return {n: CompiledFunction(lib, n) for n in self.names}
        return {n: CasadiFunction(fn) for n, fn in self._casadi_functions().items()}

    def casadi_external(self, name: str) -> ca.Function:
        """A function as a CasADi Function (for nlpsol): the compiled one, else the built one."""
        if self.load() is not None:
            return ca.external(name, str(self.path))
        return self._casadi_functions()[name]


def prefetch(loaders: Sequence[Callable[[], object]]) -> None:
    """Run ``loaders`` (each compiles or loads a library) in parallel threads: the first run on a
    machine compiles its kernels on all cores instead of one after another. Errors surface when
    the kernels are used, as they would without the prefetch."""
    if len(loaders) < 2 or compiler() is None:
        return
    from concurrent.futures import ThreadPoolExecutor
    with ThreadPoolExecutor(max_workers=min(len(loaders), os.cpu_count() or 1)) as pool:
        for future in [pool.submit(load) for load in loaders]:
            future.exception()
