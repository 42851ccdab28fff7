"""The experiment file: YAML -> validated experiment objects (the only module that imports yaml).

An experiment names a body (Appendix B), a walk (section 3: any non-empty subset of the locomotion
parameters v, sl, sf, a duration or a number of steps, and an optional per-step schedule as in
section 5), overrides of the locomotion attributes, and solver and output options::

    name: natural_walk            # a slug: also the default output folder results/<name>
    body: {height: 1.8, mass: 80} # m, kg
    walk: {speed: 5.0, duration: 12}
    attributes: {trunk_lean: 8.0}
    solver: {method: multiple-shooting}
    output: {animation: true}     # walk.gif (docs/gif.md); off unless asked for, on in configs/

Validation happens in two layers. Pydantic (strict types, ``extra="forbid"``) checks the shape;
then the model's own validators run the paper's checks (Body ranges, the attribute registry, and
eq. 1-3 for every step through :func:`klaw_ocp.gait.plan_steps`), so a file that loads also plans.
Every failure is raised as one :class:`ConfigError` whose message is one line,
``<field.path>: got <value>, allowed <...>``.

Before either layer, the YAML text itself is bounded (:func:`parse_yaml`: at most MAX_YAML_BYTES,
MAX_YAML_DEPTH levels of nesting and MAX_YAML_NODES nodes with its aliases expanded, each key
once in a mapping, safe tags only); after them, the walk's size (MAX_STEPS steps and MAX_WALK_S
seconds, MAX_STEP_INTERVALS steps x intervals, MAX_FRAMES frames of angles.csv). docs/limits.md
lists every bound and the measurements behind it.
"""
from __future__ import annotations

import math
import os
from pathlib import Path
from typing import Any, Literal, Optional

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .body import Body
from .errors import ConfigError, GaitLimitError, KlawError, out_of_range, short_repr
from .gait import LocomotionAttributes, StepPlan, plan_steps
from .gait.plan import MAX_STEPS, MAX_WALK_S

class _FieldError(ValueError):
    """Raised inside a validator; the field path is filled in from pydantic's error location."""

    def __init__(self, got: str, allowed: str):
        super().__init__(f"got {got}, allowed {allowed}")
        self.got, self.allowed = got, allowed


#: Shared pydantic settings: unknown keys are errors, no silent "5" -> 5.0, no NaN or infinity.
_STRICT = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)

SOLVER_METHODS = ("multiple-shooting", "plain-shooting")
NLP_CHOICES = ("auto", "rootfinder", "ipopt")
STANCES = ("monitored", "tracking")
LOCK_RULES = ("momentum", "zero")

# What the solvers can use (measured, docs/limits.md):
#: every subphase grid has a node on each of a step's 4 breakpoints (F_θ1 off, toe-off, the ends
#: of swing1 and swing2), so at least 5 intervals; 500 still solves (0.6x real time)
INTERVALS_RANGE = (5, 500)
#: below 1e-14 round-off keeps multiple shooting from converging; above 1e-3 (1 mm, 1 mrad at
#: heel strike) a "converged" walk no longer meets the paper's constraints
TOLERANCE_RANGE = (1e-14, 1e-3)
#: multiple shooting's Newton needs 3 iterations from its guesses (1 and 2 fail on the first
#: step); plain shooting always allows itself 60 shots; IPOPT gets 10x this
ITERATIONS_RANGE = (3, 1000)
#: the solving work of a walk: steps x intervals (1000 steps at the default 20 intervals, 200
#: steps at 100); solving time grows with both
MAX_STEP_INTERVALS = 20_000


class BodyConfig(BaseModel):
    """Body height (m) and mass (kg); ranges are checked by :class:`klaw_ocp.body.Body`."""

    model_config = _STRICT
    height: float
    mass: float


class ScheduleEntry(BaseModel):
    """From step ``step`` (0-based) on, these locomotion parameters (completed with eq. 1)."""

    model_config = _STRICT
    step: int = Field(ge=0, lt=MAX_STEPS)
    speed: Optional[float] = Field(default=None, gt=0)  # km/h
    step_length: Optional[float] = Field(default=None, gt=0)  # m
    step_frequency: Optional[float] = Field(default=None, gt=0)  # steps/min

    @model_validator(mode="after")
    def _some_parameter(self):
        if self.speed is None and self.step_length is None and self.step_frequency is None:
            raise _FieldError(f"{{step: {self.step}}} with no parameter",
                              "at least one of speed, step_length, step_frequency")
        return self


class WalkConfig(BaseModel):
    """The locomotion request: any non-empty subset of speed (km/h), step_length (m) and
    step_frequency (steps/min); exactly one of duration (s) or steps; an optional schedule.

    ``start_from_rest`` / ``end_at_rest`` ask the walk (middle level) to start from standing and
    to end standing, as in fig. 8; the high-level plan is the same either way.
    """

    model_config = _STRICT
    speed: Optional[float] = Field(default=None, gt=0)
    step_length: Optional[float] = Field(default=None, gt=0)
    step_frequency: Optional[float] = Field(default=None, gt=0)
    duration: Optional[float] = Field(default=None, gt=0, le=MAX_WALK_S)
    steps: Optional[int] = Field(default=None, ge=1, le=MAX_STEPS)
    schedule: list[ScheduleEntry] = Field(default_factory=list, max_length=MAX_STEPS)
    start_from_rest: bool = False
    end_at_rest: bool = False

    @model_validator(mode="after")
    def _duration_or_steps(self):
        if (self.duration is None) == (self.steps is None):
            got = (f"duration {self.duration:g} and steps {self.steps}" if self.duration is not None
                   else "neither duration nor steps")
            raise _FieldError(got, "exactly one of duration (s) or steps")
        return self

    def request(self) -> dict[str, Optional[float]]:
        """The base locomotion parameters as a mapping for :func:`plan_steps`."""
        return {"speed": self.speed, "step_length": self.step_length,
                "step_frequency": self.step_frequency}


class SolverConfig(BaseModel):
    """How the subphase boundary-value problems are solved (section 4.1)."""

    model_config = _STRICT
    method: Literal["multiple-shooting", "plain-shooting"] = "multiple-shooting"
    intervals: int = Field(default=20, ge=INTERVALS_RANGE[0], le=INTERVALS_RANGE[1])
    tolerance: float = Field(default=1e-9, ge=TOLERANCE_RANGE[0], le=TOLERANCE_RANGE[1])
    max_iterations: int = Field(default=50, ge=ITERATIONS_RANGE[0], le=ITERATIONS_RANGE[1])
    nlp: Literal["auto", "rootfinder", "ipopt"] = "auto"
    #: "monitored": the paper's stance (pa follows the hip sinusoid by feedback; square problem);
    #: "tracking": pa free over the grid, IPOPT tracks the sinusoid under the hip floor (multiple shooting)
    stance: Literal["monitored", "tracking"] = "monitored"
    #: what a lock does to the other rates (the stance leg reaching l1, §4.2; the knee at full
    #: extension, eq. 5; dynamics.LOCK_RULES): "momentum" conserves every other generalized
    #: momentum, "zero" (the paper's reading) sets only the locked rate to zero
    lock_rule: Literal["momentum", "zero"] = "momentum"


#: Frames per second of angles.csv (the body's motion, docs/body.md) unless ``output.fps`` says
#: otherwise, and the most it may ask for.
DEFAULT_FPS = 30.0
MAX_FPS = 1000.0
#: The most frames angles.csv may hold (output.fps x the walk's seconds): 60 s at 1000 fps, the
#: longest walk at 100 fps; the body's frames cost about 3 KB of memory each (docs/limits.md)
MAX_FRAMES = 60_000
#: The longest walk whose plots are drawn (steps): legs.png strobes every step, about 1 MB of
#: memory a step (a 1000-step walk's plots take 1.5 GB); longer walks run with --no-plots or
#: output.plots: false (docs/limits.md)
MAX_PLOTTED_STEPS = 200
#: The longest output.dir accepted (characters)
MAX_DIR_CHARS = 1024


class OutputConfig(BaseModel):
    """Where results go (default ``results/<name>``), whether to draw the plots of the run
    (``plots/``, docs/experiments.md), the frame rate of the body's angles (``angles.csv``,
    docs/body.md) and whether to render the body walking, ``walk.gif`` (docs/gif.md: a few seconds;
    off by default, on in the shipped configs, ``run --no-animation`` skips it)."""

    model_config = _STRICT
    dir: Optional[str] = Field(default=None, min_length=1, max_length=MAX_DIR_CHARS)
    plots: bool = True
    fps: float = Field(default=DEFAULT_FPS, gt=0, le=MAX_FPS)
    animation: bool = False

    @field_validator("dir")
    @classmethod
    def _a_path(cls, value):
        if value is not None and "\0" in value:
            raise _FieldError(short_repr(value), "a folder path without NUL characters")
        return value


class ExperimentConfig(BaseModel):
    """A whole experiment. Build it with :func:`load_config` or :meth:`from_mapping`."""

    model_config = _STRICT
    name: str = Field(pattern=r"^[a-z0-9_-]+$", max_length=64)
    body: BodyConfig
    walk: WalkConfig
    attributes: dict[str, float] = Field(default_factory=dict)
    solver: SolverConfig = Field(default_factory=SolverConfig)
    output: OutputConfig = Field(default_factory=OutputConfig)

    @field_validator("attributes")
    @classmethod
    def _known_attributes(cls, value):
        LocomotionAttributes.defaults().with_overrides(value)  # raises ConfigError
        return value

    @model_validator(mode="after")
    def _plannable(self):
        # The paper's own checks (Body ranges, eq. 1 limits, eq. 2, eq. 3) at load time, so that
        # a config that loads is one that can be walked; then the walk's size (docs/limits.md).
        plans = self.plan()
        check_walk_size(len(plans), self.solver.intervals)
        seconds = plans[-1].t_start + plans[-1].timings.t_step * (2 if self.walk.end_at_rest else 1)
        frames = seconds * self.output.fps
        if frames > MAX_FRAMES:
            raise ConfigError(f"output.fps: got {self.output.fps:g} frames/s for {seconds:.4g} s of walking "
                              f"({frames:.0f} frames), allowed at most {MAX_FRAMES} frames: output.fps "
                              f"<= {math.floor(MAX_FRAMES / seconds * 1000) / 1000:g} for this walk (docs/limits.md)")
        return self

    @classmethod
    def from_mapping(cls, data: Any) -> "ExperimentConfig":
        """Validate a plain mapping (as from YAML); every failure is one ConfigError line."""
        if not isinstance(data, dict):
            raise ConfigError(f"config: got {_short(data)}, allowed a mapping with name, body, walk")
        try:
            return cls.model_validate(data)
        except ValidationError as exc:
            raise _one_line(exc) from None

    def body_model(self) -> Body:
        return Body(height=self.body.height, mass=self.body.mass)

    def attributes_model(self) -> LocomotionAttributes:
        return LocomotionAttributes.defaults().with_overrides(self.attributes)

    def plan(self) -> list[StepPlan]:
        """Every step of the walk (eq. 1-3), see :func:`klaw_ocp.gait.plan_steps`."""
        schedule = [e.model_dump(exclude_none=True) for e in self.walk.schedule]
        return plan_steps(self.body_model(), self.walk.request(), schedule, n_steps=self.walk.steps,
                          duration=self.walk.duration, attributes=self.attributes_model(),
                          start_from_rest=self.walk.start_from_rest)

    def full_plan(self) -> list[StepPlan]:
        """:meth:`plan` and, for a walk that ends at rest, its closing step (sl = 0)."""
        plans = self.plan()
        if self.walk.end_at_rest:
            from .gait import closing_step
            plans.append(closing_step(self.body_model(), self.attributes_model(), plans[-1]))
        return plans

    def resolved(self) -> dict:
        """The whole experiment as a plain mapping with every default filled in, the attributes
        included: loading it again gives the same walk (``config.resolved.yaml``)."""
        data = self.model_dump(mode="json")
        data["attributes"] = self.attributes_model().as_dict()
        return data

    def resolved_yaml(self, header: str = "") -> str:
        """:meth:`resolved` as YAML (floats written exactly), after ``header`` as comment lines."""
        comment = "".join(f"# {line}\n" for line in header.splitlines())
        return comment + yaml.safe_dump(self.resolved(), sort_keys=False, allow_unicode=True)

    def output_dir(self) -> Path:
        """``output.dir`` if given, else ``results/<name>`` (relative to the working directory)."""
        return Path(self.output.dir) if self.output.dir else Path("results") / self.name


def check_walk_size(n_steps: int, intervals: int) -> None:
    """Refuse a walk whose solving work, steps x intervals, exceeds MAX_STEP_INTERVALS."""
    if n_steps * intervals > MAX_STEP_INTERVALS:
        raise ConfigError(f"solver.intervals: got {intervals} for a walk of {n_steps} steps "
                          f"({n_steps * intervals} step-intervals), allowed at most "
                          f"{max(MAX_STEP_INTERVALS // n_steps, 1)} for this walk (steps x intervals "
                          f"<= {MAX_STEP_INTERVALS}, docs/limits.md)")


def check_stance_method(stance: str, method: str, prefix: str = "") -> None:
    """The tracking stance is an optimal control problem: refuse it with plain shooting (one line)."""
    if stance == "tracking" and method != "multiple-shooting":
        raise ConfigError(f"{prefix}solver.stance: got 'tracking' with method {method!r}, allowed 'monitored' "
                          "(the tracking stance is an optimal control problem; use method multiple-shooting)")


def load_config(path, sets=()) -> ExperimentConfig:
    """Read and validate an experiment YAML file; raise one-line ConfigError on any problem.
    ``sets``: ``--set PATH=VALUE`` overrides (:mod:`klaw_ocp.config_paths`), applied before the
    validation, so an overridden value is checked like one in the file."""
    data = read_yaml_file(path)
    if sets:
        if not isinstance(data, dict):
            raise ConfigError(f"config: got {_short(data)}, allowed a mapping with name, body, walk")
        from .config_paths import apply_sets
        data = apply_sets(data, sets)
    return ExperimentConfig.from_mapping(data)


# ---------------------------------------------------------------------------------------------
# Bounded YAML: the document's size, nesting and alias expansion are checked on its parse events
# (which cost no recursion and expand no alias) before anything is built from it (docs/limits.md).

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


class _BoundedLoader(_Loader):
    """The safe loader (no Python tags), whose constructors report a value they cannot build
    (a 30 February, an integer of 5000 digits, an empty ``!!float``) as a YAML error at its line."""

    def construct_object(self, node, deep=False):
        try:
            return super().construct_object(node, deep=deep)
        except yaml.YAMLError:
            raise
        except Exception as exc:  # noqa: BLE001 - ValueError, OverflowError, PyYAML's IndexError on "!!float"
            value = short_repr(node.value, 40) if isinstance(node.value, str) else "a value"
            raise yaml.constructor.ConstructorError(None, None, f"cannot read {value} "
                                                    f"({_cut(' '.join(str(exc).split()), 80)})",
                                                    node.start_mark) from None


class _Frame:
    """An open mapping or sequence while the events are checked."""
    __slots__ = ("mapping", "anchor", "start", "level", "deepest", "children", "keys", "key")

    def __init__(self, mapping: bool, anchor, start: int, level: int):
        self.mapping, self.anchor, self.start, self.level = mapping, anchor, start, level
        self.deepest, self.children, self.keys, self.key = level, 0, {}, None


def _path_text(parts) -> str:
    out = ""
    for part in parts:
        if isinstance(part, int):
            out += f"[{part}]"
        else:
            text = part if len(part) <= 40 else part[:39] + "…"
            out += f".{text}" if out else text
    return out or "config"


def _check_events(text: str, source: str) -> None:
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
            raise ConfigError(f"{_path_text(path())}: got more than {MAX_YAML_NODES} YAML nodes "
                              f"(aliases expanded) by {where(event)} of {source}, allowed at most "
                              f"{MAX_YAML_NODES} (docs/limits.md)")
        level = len(stack) + nesting
        if level > MAX_YAML_DEPTH:
            raise ConfigError(f"{_path_text(path())}: got mappings and lists nested {level} deep "
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
                    raise ConfigError(f"{_path_text(path(name))}: got the key a second time "
                                      f"({where(event)} of {source}; first at line {first}), allowed "
                                      f"each key once in a mapping")
                frame.keys[key] = event.start_mark.line + 1
                frame.key = name
            else:
                frame.key = None
        frame.children += 1

    for event in yaml.parse(text, Loader=_Loader):
        if isinstance(event, yaml.DocumentStartEvent):
            stack, anchors = [], {}
        elif isinstance(event, yaml.ScalarEvent):
            add(event, 1, 0)
            if event.anchor is not None:
                anchors[event.anchor] = (1, 0)
            child(event)
        elif isinstance(event, yaml.AliasEvent):
            if any(frame.anchor == event.anchor for frame in stack):
                raise ConfigError(f"{_path_text(path())}: got the alias *{event.anchor} inside its own "
                                  f"anchor ({where(event)} of {source}), allowed aliases of complete "
                                  f"nodes only (a recursive document)")
            nodes, nesting = anchors.get(event.anchor, (1, 0))   # undefined: the loader says so
            add(event, nodes, nesting)
            child(("alias",))
        elif isinstance(event, (yaml.MappingStartEvent, yaml.SequenceStartEvent)):
            add(event, 1, 1)
            if stack and stack[-1].mapping and stack[-1].children % 2 == 0:
                pass  # a mapping or list as a key: the loader refuses it (unhashable)
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
        mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
        at = f" at line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
        problem = getattr(exc, "problem", None) or str(exc).splitlines()[0]
        problem = " ".join(str(problem).split())
        raise ConfigError(f"{source}: got invalid YAML{at} ({_cut(problem)}), allowed well-formed YAML "
                          f"with standard tags only (no !!python)") from None
    except RecursionError:   # pragma: no cover - the depth check comes first
        raise ConfigError(f"{source}: got YAML nested too deep, allowed at most {MAX_YAML_DEPTH} "
                          f"nested mappings and lists") from None


def _cut(text: str, limit: int = 160) -> str:
    return text if len(text) <= limit else text[: limit - 1] + "…"


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
        raise ConfigError(f"{what}: got {_short(str(path))}, a file of more than {MAX_YAML_BYTES} bytes, "
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


# ---------------------------------------------------------------------------------------------
# pydantic ValidationError -> one line "<field.path>: got <value>, allowed <...>"

_ALLOWED = {
    "float_type": "a number", "float_parsing": "a number", "finite_number": "a finite number",
    "int_type": "an integer", "int_parsing": "an integer", "int_from_float": "an integer",
    "bool_type": "true or false", "bool_parsing": "true or false",
    "string_type": "a string", "dict_type": "a mapping", "list_type": "a list",
    "model_type": "a mapping", "model_attributes_type": "a mapping",
    "string_pattern_mismatch": "a slug of lowercase letters, digits, '_' and '-'",
}
_BOUNDS = {"greater_than": "a number > {gt}", "greater_than_equal": "a number >= {ge}",
           "less_than": "a number < {lt}", "less_than_equal": "a number <= {le}",
           "string_too_long": "at most {max_length} characters", "string_too_short": "at least {min_length} character",
           "too_long": "at most {max_length} entries", "literal_error": "one of {expected}"}


def _path(loc) -> str:
    out = ""
    for part in loc:
        if part == "[key]":
            out += " (a key)"
        elif isinstance(part, int) and not isinstance(part, bool):
            out += f"[{part}]"
        else:
            text = part if isinstance(part, str) else short_repr(part, 40)
            text = text if len(text) <= 40 else text[:39] + "…"
            out += f".{text}" if out else text
    return out or "config"


def _short(value, limit: int = 60) -> str:
    return short_repr(value, limit)


def _model_at(loc):
    """The pydantic model class that owns the last key of ``loc`` (to list its allowed keys)."""
    model = ExperimentConfig
    for part in loc[:-1]:
        if isinstance(part, int):
            continue
        field = model.model_fields.get(part)
        ann = getattr(field, "annotation", None)
        inner = getattr(ann, "__args__", (ann,))[0] if ann is not None else None
        if isinstance(ann, type) and issubclass(ann, BaseModel):
            model = ann
        elif isinstance(inner, type) and issubclass(inner, BaseModel):
            model = inner
        else:
            return None
    return model


def _one_line(exc: ValidationError) -> ConfigError:
    errors = exc.errors()
    err = errors[0]
    more = f" (and {len(errors) - 1} more)" if len(errors) > 1 else ""
    cause = (err.get("ctx") or {}).get("error")
    kind, loc = err["type"], err["loc"]
    field = _path(loc)
    if isinstance(cause, KlawError):
        # Raised by the paper's checks, already one line and naming its own field path; a walk
        # outside the supported envelope stays a GaitLimitError (docs/envelope.md).
        kind_of = GaitLimitError if isinstance(cause, GaitLimitError) else ConfigError
        return kind_of(str(cause).splitlines()[0] + more)
    if isinstance(cause, _FieldError):
        return ConfigError(f"{field}: got {cause.got}, allowed {cause.allowed}{more}")
    if kind == "extra_forbidden":
        model = _model_at(loc)
        keys = ", ".join(model.model_fields) if model is not None else "the documented keys"
        return ConfigError(f"{field}: got an unknown key (value {_short(err['input'])}), allowed only the keys {keys}{more}")
    if kind == "missing":
        return ConfigError(f"{field}: got nothing, allowed a required value{more}")
    if kind == "invalid_key":   # a key that is not a string (1:, null:, a float)
        return ConfigError(f"{_path(loc[:-1])}: got the key {_short(err['input'], 40)} "
                           f"({type(err['input']).__name__}), allowed string keys only{more}")
    if kind in _BOUNDS:
        ctx = {k: (f"{v:g}" if isinstance(v, float) else v) for k, v in (err.get("ctx") or {}).items()}
        allowed = _BOUNDS[kind].format(**ctx)
    else:
        allowed = _ALLOWED.get(kind, err["msg"])
    return ConfigError(f"{field}: got {_short(err['input'])}, allowed {allowed}{more}")
