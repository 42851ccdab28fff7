"""What a walk does with the terminal: Ctrl-C (and SIGTERM) waits for the end of the step,
CasADi's own warnings are kept for summary.json instead of being printed (issue #24), and the one
pause a first run makes, compiling the solver kernels, is announced before it starts (issue #32).

- :class:`DeferredInterrupt`: CasADi checks for Ctrl-C inside IPOPT and turns a KeyboardInterrupt
  into a failed solve ("NonIpopt_Exception_Thrown", with a warning on stderr), and its wrappers
  drop one raised while the walk builds its solver, so an interrupt raised there is lost or
  reported as a solver failure. During a walk (from the solver's construction on) the first
  Ctrl-C, or SIGTERM under ``klaw-ocp``, only sets a flag, which the walk checks between steps
  (:meth:`DeferredInterrupt.check`): the walk stops at the end of the step it is solving (tens of
  milliseconds). A second one raises at once. Only in the main thread, and only over Python's
  default handler or the command's (:mod:`klaw_ocp.stop_signals`; an application's own SIGINT
  handler, or a worker that ignores SIGINT, is left alone).
- :class:`CasadiMessages`: CasADi writes its warnings through Python's ``sys.stderr``
  (``CasADi - <date> <time> WARNING("...") [file:line]``); while a walk runs, those lines are
  taken out of the stream and kept (without the date, once each); every other line goes through.
  Walks in several threads at once each keep the lines written from their own thread.
- :class:`CompileNotice`: a listener for :func:`klaw_ocp.kernels.compile_notices` that
  says, on one line on stderr, that the kernels are being compiled once for this machine, how
  long that takes and where they are kept, once, before the pause.
"""
from __future__ import annotations

import io
import os
import re
import sys
import threading

from .stop_signals import Deferred

_PREFIX = "CasADi - "
_STAMP = re.compile(r"^CasADi - \S+ \S+ ")
#: at most this many distinct CasADi messages are kept per walk
MAX_MESSAGES = 50
#: how long the first walk on a machine compiles: the natural walk's four libraries took 2.4-2.7 s
#: on a quiet 2-core machine, up to 12 s while other work loaded it, a walk that ends at rest or a
#: tracking stance a few seconds more (docs/performance.md)
COMPILE_ESTIMATE = "typically 3-10 s"


class DeferredInterrupt(Deferred):
    """Context manager: Ctrl-C or SIGTERM sets :attr:`pressed`; :meth:`check` raises
    KeyboardInterrupt then; a second one raises at once (:class:`klaw_ocp.stop_signals.Deferred`)."""


class CasadiMessages:
    """Context manager: while it is open, CasADi's lines written from this thread go to
    :attr:`messages`; every other line goes on to the stream that was ``sys.stderr``.

    ``sys.stderr`` is one for the process, and walks may run in several threads at once: the
    first open collector puts one stand-in in its place (:class:`_StderrStandIn`), which hands
    each line to the collector of the thread that wrote it (CasADi writes from the thread whose
    call warns), and the last one to close puts the stream back. Two threads that each swapped
    ``sys.stderr`` themselves would restore each other's stand-in, and a walk would keep another
    walk's warnings."""

    def __init__(self):
        self.messages: list[str] = []
        self._target = None
        self._partial = ""

    def __enter__(self) -> "CasadiMessages":
        self._target = _StderrStandIn.attach(self)
        return self

    def __exit__(self, *exc) -> None:
        _StderrStandIn.detach(self)
        if self._partial:
            self._line(self._partial, end="")
            self._partial = ""

    def write(self, text: str) -> int:
        self._partial += text
        *lines, self._partial = self._partial.split("\n")
        for line in lines:
            self._line(line)
        if self._partial and not (self._partial.startswith(_PREFIX) or _PREFIX.startswith(self._partial)):
            self._target.write(self._partial)       # not CasADi's: through at once (a prompt, a bar)
            self._partial = ""
        return len(text)

    def _line(self, line: str, end: str = "\n") -> None:
        if line.startswith(_PREFIX):
            message = _STAMP.sub("", line).strip()
            if message not in self.messages and len(self.messages) < MAX_MESSAGES:
                self.messages.append(message)
        else:
            self._target.write(line + end)


class _StderrStandIn(io.TextIOBase):
    """What ``sys.stderr`` is while collectors are open: each thread's writes go to its innermost
    open :class:`CasadiMessages` (an ``on_step`` may run a walk of its own), a thread without one
    writes straight through. It stays usable after it is taken off (a progress bar made during
    the walk closes after it), writing through to the stream it replaced."""

    _lock = threading.Lock()
    _current: "_StderrStandIn | None" = None

    def __init__(self, target):
        super().__init__()
        self.target = target
        self.open = 0
        self._collectors: dict[int, list] = {}   # thread ident -> its open collectors, innermost last

    @classmethod
    def attach(cls, collector: CasadiMessages):
        """Route this thread's writes to ``collector``; the stream it writes other lines to."""
        with cls._lock:
            stand_in = cls._current
            if stand_in is None:
                stand_in = cls._current = cls(sys.stderr)
                sys.stderr = stand_in
            stand_in.open += 1
            stand_in._collectors.setdefault(threading.get_ident(), []).append(collector)
            return stand_in.target

    @classmethod
    def detach(cls, collector: CasadiMessages) -> None:
        with cls._lock:
            stand_in = cls._current
            if stand_in is None:
                return
            stack = stand_in._collectors.get(threading.get_ident(), [])
            if collector in stack:
                stack.remove(collector)
                stand_in.open -= 1
            if not stack:
                stand_in._collectors.pop(threading.get_ident(), None)
            if stand_in.open == 0:
                cls._current = None
                if sys.stderr is stand_in:     # else someone replaced it meanwhile: theirs stays
                    sys.stderr = stand_in.target

    def write(self, text: str) -> int:
        stack = self._collectors.get(threading.get_ident())
        if stack:
            return stack[-1].write(text)
        self.target.write(text)
        return len(text)

    def writable(self) -> bool:
        return True

    @property
    def encoding(self):
        return getattr(self.target, "encoding", "utf-8")

    def flush(self) -> None:
        self.target.flush()

    def fileno(self) -> int:
        return self.target.fileno()

    def isatty(self) -> bool:
        return self.target.isatty()


class CompileNotice:
    """Called with the cache folder when the solver kernels start compiling: writes one line on
    stderr the first time, through ``tqdm.write`` so that a progress bar on the same stream is
    cleared and redrawn around it rather than run into (a library compiled mid-walk, such as
    IPOPT's, comes while the bar is shown). :attr:`told` says whether it spoke."""

    def __init__(self, prog: str):
        self.prog, self.told = prog, False
        self._lock = threading.Lock()

    def line(self, folder) -> str:
        home = os.path.expanduser("~")
        where = str(folder)
        if home not in ("", "~", os.sep) and where.startswith(home + os.sep):
            where = "~" + where[len(home):]
        return (f"{self.prog}: compiling the solver kernels for this machine, once "
                f"({COMPILE_ESTIMATE}; cached in {where})")

    def __call__(self, folder) -> None:
        with self._lock:                  # the compiles of a walk start in parallel threads
            if self.told:
                return
            self.told = True
        from tqdm import tqdm
        tqdm.write(self.line(folder), file=sys.stderr)
