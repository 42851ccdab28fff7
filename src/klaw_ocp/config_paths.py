"""Dotted config paths and their values: ``--set PATH=VALUE`` (``run``, ``validate``,
``compare``) and ``--vary PATH=VALUES`` (``sweep``, docs/sweep.md) share one syntax.

PATH names a config field through its mappings (``walk.speed``, ``attributes.toe_clearance``,
``body.height``, ``solver.intervals``). A VALUE is a YAML scalar (``4``, ``0.03``, ``true``,
``null``, ``plain-shooting``); VALUES is a comma list of them or of ranges ``start:stop:step`` that
include their stop when it is on the grid. The value is then validated like the file itself.
Every failure is one ConfigError line naming the flag and what is allowed.
"""
from __future__ import annotations

import math
import re

from .errors import ConfigError, out_of_range, short_repr

#: The largest sweep accepted (walks, counting each method separately).
MAX_WALKS = 10_000
#: A range includes its stop when (stop - start) / step is this close (relative) to an integer.
RANGE_REL_TOL = 1e-9
#: Range values are rounded to this many significant digits (0.1:0.3:0.1 gives 0.3, not 0.30000000000000004).
RANGE_DIGITS = 12
_PATH = re.compile(r"^[A-Za-z0-9_-]+(\.[A-Za-z0-9_-]+)*$")
#: The longest PATH (characters) and the most keys in it: the schema's deepest field is three deep.
MAX_PATH_CHARS = 200
MAX_PATH_KEYS = 8
#: The longest VALUE or VALUES (characters).
MAX_VALUE_CHARS = 10_000
_SET_ALLOWED = ("PATH=VALUE with PATH a dotted config path (walk.speed, attributes.toe_clearance, "
                "body.height) and VALUE one YAML scalar (4, 0.03, true, plain-shooting)")
_VARY_ALLOWED = ("PATH=VALUES with PATH a dotted config path (walk.speed) and VALUES a comma list of "
                 "YAML scalars (1,3,5 or true,false) or ranges start:stop:step with step > 0 (0.5:8:0.5)")


def _good_path(path: str) -> bool:
    return (len(path) <= MAX_PATH_CHARS and bool(_PATH.match(path))
            and path.count(".") < MAX_PATH_KEYS)


def parse_vary(text: str) -> tuple[str, list]:
    """``"walk.speed=1,3,5"`` -> ``("walk.speed", [1, 3, 5])``; one-line ConfigError otherwise."""
    path, sep, values = str(text).partition("=")
    path = path.strip()
    if not sep or not _good_path(path):
        raise ConfigError(out_of_range("--vary", text, _VARY_ALLOWED))
    if len(values) > MAX_VALUE_CHARS:
        raise ConfigError(f"--vary {path}: got {len(values)} characters of values, allowed at most {MAX_VALUE_CHARS}")
    return path, parse_values(values, path)


def parse_set(text: str) -> tuple[str, object]:
    """``"walk.speed=4"`` -> ``("walk.speed", 4)``: one YAML scalar, parsed as ``--vary`` parses
    each of its values; one-line ConfigError otherwise."""
    path, sep, value = str(text).partition("=")
    path = path.strip()
    if not sep or not _good_path(path) or not value.strip():
        raise ConfigError(out_of_range("--set", text, _SET_ALLOWED))
    if len(value) > MAX_VALUE_CHARS:
        raise ConfigError(f"--set {path}: got a value of {len(value)} characters, allowed at most {MAX_VALUE_CHARS}")
    return path, _parse_scalar(value.strip(), path, flag="--set", allowed=_SET_ALLOWED)


#: Fields of which a config gives exactly one: setting one (``--set walk.steps=300`` on a config
#: with a ``duration``, or ``--vary`` over it) removes the others, as the user means.
ALTERNATIVE_FIELDS: tuple[tuple[str, ...], ...] = (("walk.duration", "walk.steps"),)


def set_path(mapping: dict, path: str, value, flag: str = "--vary") -> None:
    """Set ``mapping[a][b][c] = value`` for ``path`` "a.b.c", creating missing mappings; a value
    (not null) for one of ALTERNATIVE_FIELDS removes the other fields of its group."""
    keys = path.split(".")
    node = mapping
    for depth, key in enumerate(keys[:-1]):
        if node.get(key) is None:
            node[key] = {}
        node = node[key]
        if not isinstance(node, dict):
            where = ".".join(keys[: depth + 1])
            raise ConfigError(f"{flag} {path}: got {where} = {short_repr(node, 60)} in the config, allowed a path "
                              f"through mappings only")
    node[keys[-1]] = value
    if value is None:
        return
    for group in ALTERNATIVE_FIELDS:
        if path in group:
            for other in group:
                parent, _, key = other.rpartition(".")
                if other != path and parent == ".".join(keys[:-1]):
                    node.pop(key, None)


def apply_sets(mapping: dict, sets) -> dict:
    """``mapping`` with every ``--set PATH=VALUE`` of ``sets`` applied in order (a later one wins)."""
    for text in sets or ():
        path, value = parse_set(text)
        set_path(mapping, path, value, flag="--set")
    return mapping


def parse_values(text: str, path: str = "PATH") -> list:
    """A comma list whose items are YAML scalars or inclusive ranges ``start:stop:step``."""
    items = [item.strip() for item in str(text).split(",")]
    if not all(items):
        raise ConfigError(f"--vary {path}: got {short_repr(text)} (an empty value), allowed {_VARY_ALLOWED}")
    values: list = []
    for item in items:
        values += _parse_range(item, path) if ":" in item else [_parse_scalar(item, path)]
        if len(values) > MAX_WALKS:
            raise ConfigError(f"--vary {path}: got more than {MAX_WALKS} values, allowed at most {MAX_WALKS} walks")
    return values


def _parse_scalar(item: str, path: str, flag: str = "--vary", allowed: str = _VARY_ALLOWED):
    from .config_yaml import parse_yaml   # the bounded safe loader of config files
    try:
        value = parse_yaml(item, f"{flag} {path}")
    except ConfigError:
        raise ConfigError(f"{flag} {path}: got {short_repr(item)}, allowed {allowed}") from None
    if not isinstance(value, (bool, int, float, str, type(None))):   # a list, a mapping, a date
        raise ConfigError(f"{flag} {path}: got {short_repr(item)}, allowed {allowed}")
    return value


def _parse_range(item: str, path: str) -> list:
    """``start:stop:step``; stop is included when it lies on the grid to within RANGE_REL_TOL."""
    parts = item.split(":")
    try:
        if len(parts) != 3:
            raise ValueError
        start, stop, step = (int(p) if re.fullmatch(r"\s*[-+]?\d+\s*", p) else float(p) for p in parts)
    except ValueError:
        raise ConfigError(f"--vary {path}: got {short_repr(item)}, allowed a range start:stop:step of numbers "
                          f"(0.5:8:0.5)") from None
    try:
        finite = all(math.isfinite(x) for x in (start, stop, step))   # an int beyond float: OverflowError
        span = (stop - start) / step if finite and step > 0 else None
        whole = round(span) if span is not None else None
    except OverflowError:
        finite = False
    if not finite or step <= 0:
        raise ConfigError(f"--vary {path}: got range {short_repr(item)}, allowed finite numbers with step > 0")
    count = (whole if abs(span - whole) <= RANGE_REL_TOL * max(1.0, abs(span)) else math.floor(span)) + 1
    if count < 1:
        raise ConfigError(f"--vary {path}: got range {short_repr(item)}, which yields no value, allowed start <= stop")
    if count > MAX_WALKS:
        raise ConfigError(f"--vary {path}: got range {short_repr(item)} with {count if count < 10**9 else f'{float(count):.3g}'} values, allowed at most {MAX_WALKS} walks")
    if all(isinstance(x, int) for x in (start, stop, step)):
        return [start + i * step for i in range(count)]
    # RANGE_DIGITS significant digits of the range's scale: 0.30000000000000004 -> 0.3, 5.6e-17 -> 0
    digits = RANGE_DIGITS - 1 - math.floor(math.log10(max(abs(start), abs(stop), step)))
    return [round(start + i * step, digits) + 0.0 for i in range(count)]


def format_value(value) -> str:
    """A varied value as written on the command line (YAML style: true, null, 0.5)."""
    if value is None:
        return "null"
    if isinstance(value, bool):
        return "true" if value else "false"
    return repr(value) if isinstance(value, float) else str(value)


def combination_label(values: dict) -> str:
    return ", ".join(f"{path}={format_value(v)}" for path, v in values.items())
