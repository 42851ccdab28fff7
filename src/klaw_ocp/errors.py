"""The exception hierarchy of klaw_ocp.

Every error a user can cause or act on derives from :class:`KlawError`, so a caller (the CLI in
particular) can catch one type and print one line. Messages name the offending field, the value
received and what is allowed.
"""
from __future__ import annotations

import math
import numbers
import reprlib


class KlawError(Exception):
    """Base class of every error raised deliberately by klaw_ocp."""


class ConfigError(KlawError, ValueError):
    """A configuration value or API argument is malformed or out of its documented range."""


class GaitLimitError(ConfigError):
    """Locomotion parameters that are well-formed but outside the anatomical limits (section 3),
    or a walk outside the supported envelope (docs/envelope.md). A kind of :class:`ConfigError`:
    ``except ConfigError`` catches every input refused before solving."""


class ConvergenceError(KlawError, RuntimeError):
    """A subphase boundary-value problem did not meet its final conditions.

    Carries the step index, the subphase name and the residual so that a caller can report them
    and keep the steps completed before it; when the solver's solution is known (raised by the
    step controller), also its ``iterations``, ``path_min``, ``nlp``, whether its trajectory is
    finite, and the solver's iteration limit, from which :attr:`cause` names the real cause.
    """

    def __init__(self, step: int, subphase: str, residual: float, detail: str = "", partial=None, *,
                 iterations: int | None = None, path_min: float | None = None, nlp: str = "",
                 finite: bool = True, max_iterations: int | None = None, where: str = ""):
        self.step = step
        self.subphase = subphase
        self.residual = residual
        self.detail = detail
        self.partial = partial
        self.iterations, self.path_min, self.nlp = iterations, path_min, nlp
        self.finite, self.max_iterations, self.where = finite, max_iterations, where
        msg = f"{where}: " if where else ""
        msg += f"step {step}, subphase {subphase!r}: did not converge (residual {residual:.3g})"
        if detail:
            msg += f": {detail}"
        super().__init__(msg)

    def within(self, where: str) -> "ConvergenceError":
        """The same failure, its message opening with ``where`` (e.g. the config it walked)."""
        return ConvergenceError(self.step, self.subphase, self.residual, self.detail, self.partial,
                                iterations=self.iterations, path_min=self.path_min, nlp=self.nlp,
                                finite=self.finite, max_iterations=self.max_iterations, where=where)

    @property
    def cause(self) -> str:
        """What stopped the solve, in words: NaN or inf, an iteration limit, IPOPT's status, a
        violated path constraint, an implausible motion, or the final conditions not met
        (several joined by "; "); the detail itself when the solver's solution is unknown."""
        return failure_cause(self.residual, self.detail, self.iterations, self.path_min, self.nlp,
                             self.finite, self.max_iterations)

    def as_dict(self) -> dict:
        """The failure as summary.json records it (``message``: the solver's own words)."""
        return {"step": int(self.step), "subphase": str(self.subphase), "residual": finite_real(self.residual),
                "cause": self.cause, "message": self.detail,
                "iterations": None if self.iterations is None else int(self.iterations),
                "path_min": finite_real(self.path_min), "nlp": self.nlp}


#: the margin below which a path constraint counts as violated (the solvers' own)
PATH_TOLERANCE = 1e-7


def failure_cause(residual: float, message: str = "", iterations: int | None = None,
                  path_min: float | None = None, nlp: str = "", finite: bool = True,
                  max_iterations: int | None = None) -> str:
    """Classify a failed subphase solve from what its solution reports (see
    :attr:`ConvergenceError.cause`); the solvers' behaviour is not changed by it."""
    if iterations is None and path_min is None and not nlp:
        return message or "final conditions not met"
    causes = []
    if not finite or residual is None or not math.isfinite(float(residual)):
        causes.append("NaN or inf in the solution (the motion diverged)")
    status = message.strip() if nlp == "ipopt" and message and " " not in message.strip() else ""
    if status == "Maximum_Iterations_Exceeded":
        causes.append(f"iteration limit: IPOPT stopped after {iterations} iterations")
    elif status:
        causes.append(f"IPOPT: {status}")
    elif (nlp == "rootfinder" and max_iterations is not None and iterations is not None
          and iterations >= max_iterations):
        causes.append(f"iteration limit: {iterations} Newton iterations (solver.max_iterations)")
    if path_min is not None and math.isfinite(path_min) and path_min < -PATH_TOLERANCE:
        causes.append(f"path constraint violated by {-path_min:.3g}")
    if "implausible motion" in message:
        causes.append("implausible motion (a root far from any walk)")
    if not causes:
        causes.append(f"final conditions not met (residual {residual:.3g})")
    return "; ".join(causes)


class ResultsNotWritten(KlawError):
    """Writing a command's results failed (an OSError: a full disk, a permission lost, a folder
    removed): the message names the path, the cause and where what was written is kept. The
    command line prints it as one line and exits 74 (``klaw_ocp.commands.EXIT_WRITE_FAILED``)."""


def os_error_text(exc: OSError) -> str:
    """An OSError in a few words: the path (both of a rename) and the system's cause, e.g.
    ``/tmp/out/walk.bvh: No space left on device``."""
    cause = exc.strerror or one_line(exc) or type(exc).__name__
    paths = [str(p) for p in (exc.filename, exc.filename2) if p is not None]
    return f"{' -> '.join(paths)}: {cause}" if paths else cause


class Interrupted(KeyboardInterrupt):
    """Ctrl-C: a KeyboardInterrupt whose ``partial`` is what was completed before it: the
    :class:`~klaw_ocp.walk.Walk` of the completed steps (``status == "interrupted"``) for
    :func:`~klaw_ocp.walk.simulate_walk`, the finished rows for :func:`~klaw_ocp.sweep.run_sweep`."""

    def __init__(self, partial=None):
        super().__init__("interrupted")
        self.partial = partial


def finite_real(value) -> float | None:
    """``value`` as a float if it is a real number (not a bool) that a float holds finitely;
    else None (NaN, infinities, an int beyond 1.8e308, a string, None, ...)."""
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        return None
    try:
        value = float(value)
    except (OverflowError, ValueError, TypeError):
        return None
    return value if math.isfinite(value) else None


#: The longest value a message quotes (characters of its repr); longer ones are cut with "…".
MAX_QUOTED = 100

_REPR = reprlib.Repr()
_REPR.maxlevel, _REPR.maxdict, _REPR.maxlist, _REPR.maxtuple, _REPR.maxset = 3, 6, 6, 6, 6
_REPR.maxstring = _REPR.maxother = _REPR.maxlong = 4 * MAX_QUOTED   # reprlib cuts in the middle beyond


def short_repr(value, limit: int = MAX_QUOTED) -> str:
    """``repr(value)`` on one line, at most ``limit`` characters (cut with "…"), whatever the
    value: deeply nested, self-referencing or huge containers are abbreviated, never expanded."""
    try:
        text = _REPR.repr(value)
    except ValueError:  # an int too long to print (sys.get_int_max_str_digits)
        text = f"<an integer of {value.bit_length()} bits>" if isinstance(value, int) else f"<{type(value).__name__}>"
    except Exception:  # noqa: BLE001 - a value whose repr fails is still reported
        text = f"<{type(value).__name__}>"
    return cut(one_line(text), limit)


def one_line(text) -> str:
    """``str(text)`` with every run of white space (newlines too) folded into one space."""
    return " ".join(str(text).split())


def cut(text: str, limit: int) -> str:
    """``text`` if it has at most ``limit`` characters, else its first ``limit - 1`` and "…"."""
    return text if len(text) <= limit else text[: limit - 1] + "…"


#: The longest key a field path names (characters); longer ones are cut with "…".
MAX_PATH_KEY = 40


def field_path(parts) -> str:
    """A config field as messages name it, from its keys and list indices:
    ``walk.schedule[2].speed``; each key cut to MAX_PATH_KEY characters (one that is not a string
    by its :func:`short_repr`); ``config`` for the document itself."""
    out = ""
    for part in parts:
        if isinstance(part, int) and not isinstance(part, bool):
            out += f"[{part}]"
        else:
            text = cut(part if isinstance(part, str) else short_repr(part, MAX_PATH_KEY), MAX_PATH_KEY)
            out += f".{text}" if out else text
    return out or "config"


def out_of_range(field: str, value, allowed: str) -> str:
    """The one-line message format shared by every range check (the value quoted by
    :func:`short_repr`)."""
    return f"{field}: got {short_repr(value)}, allowed {allowed}"
