"""Solvers for the subphase boundary-value problems, chosen by name (section 4.1).

Both modes take a :class:`SubphaseProblem` and return a :class:`SubphaseSolution`:

- multiple shooting (:data:`klaw_ocp.choices.MULTIPLE_SHOOTING`): CasADi multiple shooting,
  ``rootfinder`` or IPOPT;
- plain shooting (:data:`klaw_ocp.choices.PLAIN_SHOOTING`): forward integration with events,
  bisection then secant (the paper).

The solvers know nothing of the walk, the configuration files, the CLI or plotting.
"""
from __future__ import annotations

from .. import choices
from ..errors import ConfigError, out_of_range
from .multiple_shooting import MultipleShootingSolver
from .plain_shooting import PlainShootingSolver
from .problem import Event, SubphaseProblem, SubphaseSolution, SubphaseSpec, time_grid

#: The solver of each method of klaw_ocp.choices.METHODS (a test holds the two equal).
SOLVERS = {MultipleShootingSolver.name: MultipleShootingSolver, PlainShootingSolver.name: PlainShootingSolver}
NLP_CHOICES = choices.NLPS


def make_solver(method: str, *, intervals: int = choices.DEFAULT_INTERVALS, substeps: int = choices.SUBSTEPS,
                tolerance: float = choices.DEFAULT_TOLERANCE, max_iterations: int = choices.DEFAULT_MAX_ITERATIONS,
                nlp: str = choices.DEFAULT_NLP):
    """A solver by name, with the options both modes share."""
    if method not in SOLVERS:
        raise ConfigError(out_of_range("solver.method", method, " or ".join(repr(m) for m in SOLVERS)))
    if nlp not in NLP_CHOICES:
        raise ConfigError(out_of_range("solver.nlp", nlp, " or ".join(repr(m) for m in NLP_CHOICES)))
    if method == MultipleShootingSolver.name:
        return MultipleShootingSolver(intervals, substeps, tolerance, max_iterations, nlp)
    return PlainShootingSolver(intervals, substeps, tolerance, max(max_iterations, 60))


__all__ = ["SOLVERS", "make_solver", "MultipleShootingSolver", "PlainShootingSolver", "Event",
           "SubphaseProblem", "SubphaseSolution", "SubphaseSpec", "time_grid"]
