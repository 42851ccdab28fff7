"""How a command stops: Ctrl-C (SIGINT) and SIGTERM (what ``kill``, systemd, a batch scheduler or
a container stop send) end it the same way, its completed results kept (issue #37, docs/experiments.md).

- :class:`CommandSignals`: for the length of a ``klaw-ocp`` command, SIGTERM raises
  KeyboardInterrupt in the main thread as Ctrl-C does, and every stop signal is recorded, so that
  the command can say which one came (:func:`stopped_words`) and notice one that never reached it
  (:func:`requested`, :func:`received`): CasADi's SWIG wrappers drop a KeyboardInterrupt raised inside a call that
  calls back into Python (seen while a walk builds its solver).
- :class:`Deferred`: within the block a stop signal only sets a flag (:meth:`Deferred.check`
  raises then); a walk uses it between steps (:class:`klaw_ocp.console.DeferredInterrupt`), and
  :func:`deferred` for what must not be cut in half (two folders swapped, a worker process being
  started: a worker handed half its data prints a traceback).
- :func:`blocked`: the stop signals blocked in this thread, for starting a process that must
  never see Ctrl-C: it inherits the mask (the drawing workers' forkserver and, through it, every
  worker; a sweep's workers: the terminal sends Ctrl-C to each process of the job, and only this
  one should answer).

Only in the main thread, and only over the handlers that raise KeyboardInterrupt (Python's own
for SIGINT, the command's): an application's own handler, or a SIGINT ignored by ``nohup``, is
left alone. This module imports nothing of the package.
"""
from __future__ import annotations

import signal
import threading
from contextlib import contextmanager

#: the signals that stop a command, and how its one line and an interrupted walk's message say
#: what each did (as a shell says it of a process: Ctrl-C interrupts, SIGTERM terminates)
STOPPED_WORDS = {signal.SIGINT: "interrupted (Ctrl-C)", signal.SIGTERM: "terminated (SIGTERM)"}
STOP_SIGNALS = tuple(STOPPED_WORDS)

_received: list[int] = []       # the stop signals received since the command began


def _main_thread() -> bool:
    return threading.current_thread() is threading.main_thread()


def _raise_interrupt(signum, frame) -> None:
    """The command's handler of SIGINT and SIGTERM: Python's Ctrl-C, recorded."""
    _received.append(signum)
    raise KeyboardInterrupt


def requested() -> bool:
    """Whether a stop signal came since the command began (even one a library swallowed)."""
    return bool(_received)


def received() -> int:
    """How many stop signals came so far: a library function that outlives one (a sweep walking in
    this process) compares two counts, so that one recorded before it began (a Ctrl-C of an
    earlier walk in the same interpreter) does not stop it."""
    return len(_received)


def stopped_words() -> str:
    """What the first stop signal did, in the command's line and the walk's message: "interrupted
    (Ctrl-C)" (also when none came) or "terminated (SIGTERM)"."""
    first = _received[0] if _received else signal.SIGINT
    return STOPPED_WORDS.get(first, STOPPED_WORDS[signal.SIGINT])


def terminated() -> bool:
    """Whether the command was stopped by SIGTERM (exit 143) rather than Ctrl-C (exit 130)."""
    return bool(_received) and _received[0] == signal.SIGTERM


def _ours(signum) -> bool:
    """Whether ``signum``'s handler raises KeyboardInterrupt and so may be deferred."""
    handler = signal.getsignal(signum)
    return handler is _raise_interrupt or (signum == signal.SIGINT and handler is signal.default_int_handler)


class CommandSignals:
    """Context manager around a command: SIGINT (over Python's handler) and SIGTERM (over the
    default, which ends the process without a word) raise KeyboardInterrupt, recorded."""

    def __init__(self):
        self._old: dict = {}

    def __enter__(self) -> "CommandSignals":
        _received.clear()
        if _main_thread():
            for signum, default in ((signal.SIGINT, signal.default_int_handler), (signal.SIGTERM, signal.SIG_DFL)):
                if signal.getsignal(signum) is default:
                    self._old[signum] = signal.signal(signum, _raise_interrupt)
        return self

    def __exit__(self, *exc) -> None:
        for signum, handler in self._old.items():
            signal.signal(signum, handler)
        self._old = {}


class Deferred:
    """Context manager: a stop signal sets :attr:`pressed`; :meth:`check` raises KeyboardInterrupt
    then. With ``second_raises`` a second signal raises at once (a user who insists)."""

    def __init__(self, second_raises: bool = True):
        self.pressed = 0
        self.second_raises = second_raises
        self._old: dict = {}

    def __enter__(self):
        if _main_thread():
            for signum in STOP_SIGNALS:
                if _ours(signum):
                    self._old[signum] = signal.signal(signum, self._handler)
        return self

    def _handler(self, signum, frame) -> None:
        _received.append(signum)
        self.pressed += 1
        if self.pressed > 1 and self.second_raises:
            raise KeyboardInterrupt

    def check(self) -> None:
        if self.pressed:
            raise KeyboardInterrupt

    def __exit__(self, *exc) -> None:
        for signum, handler in self._old.items():
            signal.signal(signum, handler)
        self._old = {}


@contextmanager
def deferred():
    """The block runs to its end whatever stop signals come; one that came raises
    KeyboardInterrupt after it (if the block itself raised nothing)."""
    with Deferred(second_raises=False) as held:
        yield
    held.check()


@contextmanager
def blocked(signals=(signal.SIGINT,)):
    """``signals`` blocked in this thread's mask for the block (a process started here inherits
    the mask and keeps it: the forkserver and its workers never see Ctrl-C); a no-op off the main
    thread or where masks are unknown."""
    if not hasattr(signal, "pthread_sigmask") or not _main_thread():
        yield
        return
    old = signal.pthread_sigmask(signal.SIG_BLOCK, set(signals))
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, old)
