"""The bounded YAML of experiment files and ``--set`` values (docs/limits.md): the document's
size, nesting and alias expansion are checked on its parse events (which cost no recursion and
expand no alias) before anything is built from it; keys appear once in a mapping; safe tags only.
Every failure is one :class:`~klaw_ocp.errors.ConfigError` line naming its source.
:mod:`klaw_ocp.config` validates what this returns."""
from __future__ import annotations

import os
import re
from pathlib import Path

import yaml

from .errors import ConfigError, cut, field_path, one_line, out_of_range, short_repr


#: The largest config file or YAML text read (bytes). The shipped configs are 1-2 KB; a schedule
#: with an entry for every one of MAX_STEPS steps takes about 30 KB.
MAX_YAML_BYTES = 64 * 1024
#: The deepest nesting of mappings and lists, aliases expanded (the schema needs 3:
#: walk -> schedule -> entry).
MAX_YAML_DEPTH = 10
#: The most nodes (scalars, mappings, lists) a document may hold, every alias counted as the
#: node it stands for: an "alias bomb" (a billion laughs) is refused at this count.
MAX_YAML_NODES = 20_000

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)   # libyaml when present: ~20x faster

#: A number with an exponent and no dot (``1e-9``, ``5e3``, ``-2E-4``, ``.5e3``) or an exponent
#: without its sign (``1.0e5``): YAML 1.2 and every reader take them for floats, YAML 1.1 (PyYAML)
#: for text. The one resolver every config file and ``--set``/``--vary`` value is read with.
YAML12_FLOAT = re.compile(r"^[-+]?(?:[0-9][0-9_]*(?:\.[0-9_]*)?|\.[0-9_]+)[eE][-+]?[0-9]+$")


class _BoundedLoader(_Loader):
    """The safe loader (no Python tags), whose constructors report a value they cannot build
    (a 30 February, an integer of 5000 digits, an empty ``!!float``) as a YAML error at its line,
    and which reads YAML 1.2's exponent floats as floats (YAML12_FLOAT)."""

    def construct_object(self, node, deep=False):
        try:
            return super().construct_object(node, deep=deep)
        except yaml.YAMLError:
            raise
        except Exception as exc:  # noqa: BLE001 - ValueError, OverflowError, PyYAML's IndexError on "!!float"
            value = short_repr(node.value, 40) if isinstance(node.value, str) else "a value"
            raise yaml.constructor.ConstructorError(None, None, f"cannot read {value} "
                                                    f"({cut(one_line(exc), 80)})",
                                                    node.start_mark) from None


_BoundedLoader.add_implicit_resolver("tag:yaml.org,2002:float", YAML12_FLOAT, list("-+0123456789."))


class _Frame:
    """An open mapping or sequence while the events are checked."""
    __slots__ = ("mapping", "anchor", "start", "level", "deepest", "children", "keys", "key")

    def __init__(self, mapping: bool, anchor, start: int, level: int):
        self.mapping, self.anchor, self.start, self.level = mapping, anchor, start, level
        self.deepest, self.children, self.keys, self.key = level, 0, {}, None


def _check_events(text: str, source: str, loader=None) -> None:
    """Refuse, on the parse events alone, a document nested deeper than MAX_YAML_DEPTH, with more
    than MAX_YAML_NODES nodes once its aliases are expanded, with an alias inside its own anchor,
    or with a key given twice in one mapping."""
    stack: list[_Frame] = []
    anchors: dict[str, tuple[int, int]] = {}      # anchor -> (nodes, nesting) of its node
    count = 0

    def where(event) -> str:
        return f"line {event.start_mark.line + 1}"

    def path(extra=None) -> list:
        parts = []
        for frame in stack:
            if frame.mapping:
                if frame.children % 2 == 1 and frame.key is not None:
                    parts.append(frame.key)
            else:
                parts.append(frame.children)
        return parts if extra is None else parts + [extra]

    def add(event, nodes: int, nesting: int) -> None:
        # a node of ``nodes`` nodes nested ``nesting`` deep goes into the innermost open frame
        nonlocal count
        count += nodes
        if count > MAX_YAML_NODES:
            raise ConfigError(f"{field_path(path())}: got more than {MAX_YAML_NODES} YAML nodes "
                              f"(aliases expanded) by {where(event)} of {source}, allowed at most "
                              f"{MAX_YAML_NODES} (docs/limits.md)")
        level = len(stack) + nesting
        if level > MAX_YAML_DEPTH:
            raise ConfigError(f"{field_path(path())}: got mappings and lists nested {level} deep "
                              f"({where(event)} of {source}{', an alias expanded' if isinstance(event, yaml.AliasEvent) else ''}), "
                              f"allowed at most {MAX_YAML_DEPTH} (docs/limits.md)")
        if stack:
            stack[-1].deepest = max(stack[-1].deepest, level)

    def key_of(event):
        # a scalar key as the constructor will see it: "walk" and 'walk' are one key
        if isinstance(event, yaml.ScalarEvent):
            return event.value if event.implicit[0] or event.tag in (None, "!", "tag:yaml.org,2002:str") \
                else (event.tag, event.value)
        return None

    def child(event) -> None:
        # bookkeeping of the innermost frame once one of its children is complete
        if not stack:
            return
        frame = stack[-1]
        if frame.mapping and frame.children % 2 == 0:
            key = key_of(event) if not isinstance(event, tuple) else None
            if key is not None:
                name = key if isinstance(key, str) else key[1]
                first = frame.keys.get(key)
                if first is not None and name != "<<":
                    raise ConfigError(f"{field_path(path(name))}: got the key a second time "
                                      f"({where(event)} of {source}; first at line {first}), allowed "
                                      f"each key once in a mapping")
                frame.keys[key] = event.start_mark.line + 1
                frame.key = name
            else:
                frame.key = None
        frame.children += 1

    for event in yaml.parse(text, Loader=loader or _Loader):
        if isinstance(event, yaml.DocumentStartEvent):
            stack, anchors = [], {}
        elif isinstance(event, yaml.ScalarEvent):
            add(event, 1, 0)
            if event.anchor is not None:
                anchors[event.anchor] = (1, 0)
            child(event)
        elif isinstance(event, yaml.AliasEvent):
            if any(frame.anchor == event.anchor for frame in stack):
                raise ConfigError(f"{field_path(path())}: got the alias *{event.anchor} inside its own "
                                  f"anchor ({where(event)} of {source}), allowed aliases of complete "
                                  f"nodes only (a recursive document)")
            nodes, nesting = anchors.get(event.anchor, (1, 0))   # undefined: the loader says so
            add(event, nodes, nesting)
            child(("alias",))
        elif isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            add(event, 1, 1)       # (a mapping or list as a key: the loader refuses it, unhashable)
            stack.append(_Frame(isinstance(event, yaml.MappingStartEvent), event.anchor, count - 1,
                                len(stack) + 1))
        elif isinstance(event, (yaml.MappingEndEvent, yaml.SequenceEndEvent)):
            frame = stack.pop()
            if frame.anchor is not None:
                anchors[frame.anchor] = (count - frame.start, frame.deepest - frame.level + 1)
            if stack:
                stack[-1].deepest = max(stack[-1].deepest, frame.deepest)
            child(("collection",))


def parse_yaml(text: str, source: str = "config"):
    """A YAML text (a config file's, or a ``--set`` value) as plain Python data, within
    MAX_YAML_BYTES, MAX_YAML_DEPTH and MAX_YAML_NODES, with no key twice in a mapping and no
    Python tags (safe loading only); every failure one ConfigError line naming ``source``."""
    if not isinstance(text, str):
        raise ConfigError(out_of_range(source, text, "YAML text (a str)"))
    size = len(text.encode("utf-8", "surrogatepass"))
    if size > MAX_YAML_BYTES:
        raise ConfigError(f"{source}: got {size} bytes of YAML, allowed at most {MAX_YAML_BYTES} "
                          f"bytes (docs/limits.md)")
    try:
        _check_events(text, source)
        return yaml.load(text, Loader=_BoundedLoader)   # noqa: S506 - a SafeLoader subclass
    except yaml.YAMLError as exc:
        # Our limits are ours whichever parser notices first: libyaml scans a flow collection
        # ahead of its events and may stop a deep one with its own nesting limit (PyYAML 6.0.4:
        # 1000 levels) before the event check sees level MAX_YAML_DEPTH + 1. PyYAML's own parser
        # yields its events one at a time, so it meets our checks first (this costs time only
        # for a document that is refused anyway).
        if _Loader is not yaml.SafeLoader:
            try:
                _check_events(text, source, loader=yaml.SafeLoader)
            except yaml.YAMLError:
                pass
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        raise ConfigError(f"{source}: got invalid YAML{at} ({cut(one_line(problem), 160)}), allowed well-formed YAML "
                          f"with standard tags only (no !!python)") from None
    except RecursionError:   # pragma: no cover - the depth check comes first
        raise ConfigError(f"{source}: got YAML nested too deep, allowed at most {MAX_YAML_DEPTH} "
                          f"nested mappings and lists") from None


def read_yaml_file(path, what: str = "config"):
    """The data of the YAML file at ``path`` (str or os.PathLike): at most MAX_YAML_BYTES read
    (a device or a huge file is refused, not read to its end), then :func:`parse_yaml`. An empty
    file is refused."""
    if isinstance(path, bool) or not isinstance(path, (str, os.PathLike)):
        raise ConfigError(out_of_range(what, path, "the path of a YAML file (a str or os.PathLike)"))
    try:
        path = Path(path)
        with open(path, "rb") as fh:
            raw = fh.read(MAX_YAML_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(out_of_range(what, str(path), "an existing YAML file (not found)")) from None
    except (OSError, ValueError) as exc:   # a folder, no permission, a NUL in the name, ...
        raise ConfigError(out_of_range(what, str(path), f"a readable UTF-8 YAML file "
                                       f"({type(exc).__name__})")) from None
    if len(raw) > MAX_YAML_BYTES:
        raise ConfigError(f"{what}: got {short_repr(str(path), 60)}, a file of more than {MAX_YAML_BYTES} bytes, "
                          f"allowed at most {MAX_YAML_BYTES} bytes of YAML (docs/limits.md)")
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise ConfigError(out_of_range(what, str(path), f"a readable UTF-8 YAML file "
                                       f"({type(exc).__name__} at byte {exc.start})")) from None
    data = parse_yaml(text, str(path))
    if data is None:
        raise ConfigError(out_of_range(what, f"{path} (empty)", "a mapping with name, body, walk"))
    return data
