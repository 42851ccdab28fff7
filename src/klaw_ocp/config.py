"""The experiment file: YAML -> validated experiment objects (with :mod:`.config_yaml`, the only modules that import yaml).

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
from pathlib import Path
from typing import Any, Literal, Optional

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from . import choices
from .body import Body
from .errors import ConfigError, GaitLimitError, KlawError, field_path, short_repr
from .gait import LocomotionAttributes, StepPlan, plan_steps
from .gait.plan import MAX_STEPS, MAX_WALK_S
from .config_yaml import read_yaml_file

class _FieldError(ValueError):
    """Raised inside a validator; the field path is filled in from pydantic's error location."""

    def __init__(self, got: str, allowed: str):
        super().__init__(f"got {got}, allowed {allowed}")
        self.got, self.allowed = got, allowed


#: The longest value a config message quotes: shorter than errors.MAX_QUOTED, the line also names
#: the field's path and what it allows
_QUOTED = 60

#: Shared pydantic settings: unknown keys are errors, no silent "5" -> 5.0, no NaN or infinity.
_STRICT = ConfigDict(extra="forbid", strict=True, allow_inf_nan=False, frozen=True)

SOLVER_METHODS, NLP_CHOICES, STANCES, LOCK_RULES = choices.METHODS, choices.NLPS, choices.STANCES, choices.LOCK_RULES

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
    """From step ``step`` (0-based) on, these locomotion parameters (completed with eq. 1) and
    these values of the attributes that may change per step (``STEP_ATTRIBUTES``); between two
    entries that give a value, it moves linearly from step to step."""

    model_config = _STRICT
    step: int = Field(ge=0, lt=MAX_STEPS)
    speed: Optional[float] = Field(default=None, gt=0)  # km/h
    step_length: Optional[float] = Field(default=None, gt=0)  # m
    step_frequency: Optional[float] = Field(default=None, gt=0)  # steps/min
    attributes: Optional[dict[str, float]] = None

    @model_validator(mode="after")
    def _some_parameter(self):
        if self.speed is None and self.step_length is None and self.step_frequency is None and not self.attributes:
            raise _FieldError(f"{{step: {self.step}}} with no parameter",
                              "at least one of speed, step_length, step_frequency, attributes")
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
    method: Literal[choices.METHODS] = choices.DEFAULT_METHOD
    intervals: int = Field(default=choices.DEFAULT_INTERVALS, ge=INTERVALS_RANGE[0], le=INTERVALS_RANGE[1])
    tolerance: float = Field(default=choices.DEFAULT_TOLERANCE, ge=TOLERANCE_RANGE[0], le=TOLERANCE_RANGE[1])
    max_iterations: int = Field(default=choices.DEFAULT_MAX_ITERATIONS, ge=ITERATIONS_RANGE[0],
                                le=ITERATIONS_RANGE[1])
    #: klaw_ocp.choices says what each of these means
    nlp: Literal[choices.NLPS] = choices.DEFAULT_NLP
    stance: Literal[choices.STANCES] = choices.DEFAULT_STANCE
    lock_rule: Literal[choices.LOCK_RULES] = choices.DEFAULT_LOCK_RULE


#: Frames per second of angles.csv (the body's motion, docs/body.md) unless ``output.fps`` says
#: otherwise, and the most it may ask for.
DEFAULT_FPS = 30.0
MAX_FPS = 1000.0
#: The most frames angles.csv may hold (output.fps x the walk's seconds): 60 s at 1000 fps, the
#: longest walk at 100 fps; the body's frames cost about 3 KB of memory each (docs/limits.md)
MAX_FRAMES = 60_000
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
            raise ConfigError(f"config: got {short_repr(data, _QUOTED)}, allowed a mapping with name, body, walk")
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
    if stance == choices.TRACKING and method != choices.MULTIPLE_SHOOTING:
        raise ConfigError(f"{prefix}solver.stance: got {choices.TRACKING!r} with method {method!r}, allowed "
                          f"{choices.MONITORED!r} (the tracking stance is an optimal control problem; use "
                          f"method {choices.MULTIPLE_SHOOTING})")


def load_config(path, sets=()) -> ExperimentConfig:
    """Read and validate an experiment YAML file; raise one-line ConfigError on any problem.
    ``sets``: ``--set PATH=VALUE`` overrides (:mod:`klaw_ocp.config_paths`), applied before the
    validation, so an overridden value is checked like one in the file."""
    data = read_yaml_file(path)
    if sets:
        if not isinstance(data, dict):
            raise ConfigError(f"config: got {short_repr(data, _QUOTED)}, allowed a mapping with name, body, walk")
        from .config_paths import apply_sets
        data = apply_sets(data, sets)
    return ExperimentConfig.from_mapping(data)


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
    # pydantic ends the location of a key that fails its own check with the marker "[key]"
    if loc and loc[-1] == "[key]":
        return (field_path(loc[:-1]) if len(loc) > 1 else "") + " (a key)"
    return field_path(loc)


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
        return ConfigError(f"{field}: got an unknown key (value {short_repr(err['input'], _QUOTED)}), allowed only the keys {keys}{more}")
    if kind == "missing":
        return ConfigError(f"{field}: got nothing, allowed a required value{more}")
    if kind == "invalid_key":   # a key that is not a string (1:, null:, a float)
        return ConfigError(f"{_path(loc[:-1])}: got the key {short_repr(err['input'], 40)} "
                           f"({type(err['input']).__name__}), allowed string keys only{more}")
    if kind in _BOUNDS:
        ctx = {k: (f"{v:g}" if isinstance(v, float) else v) for k, v in (err.get("ctx") or {}).items()}
        allowed = _BOUNDS[kind].format(**ctx)
    else:
        allowed = _ALLOWED.get(kind, err["msg"])
    return ConfigError(f"{field}: got {short_repr(err['input'], _QUOTED)}, allowed {allowed}{more}")
