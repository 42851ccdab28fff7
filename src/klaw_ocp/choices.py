"""Every named choice of how a walk is solved, and the solver defaults, written once.

The config schema, the solvers' registry, the walk, the command-line choices, ``compare``,
``sweep`` and ``reproduce`` all read these names from here (a test holds the solvers' registry,
the config's choices and the CLI's ``--method`` equal), so a new solver mode is its module, one
entry in :data:`METHODS` and one in ``klaw_ocp.solvers.SOLVERS``. This module imports nothing.
"""
from __future__ import annotations

#: CasADi multiple shooting: Newton on the shooting conditions (``rootfinder``), IPOPT when a path
#: inequality is active (docs/solvers.md).
MULTIPLE_SHOOTING = "multiple-shooting"
#: The paper's plain shooting: forward integration with events, bisection then secant (§4.1).
PLAIN_SHOOTING = "plain-shooting"
#: The solver methods (``solver.method``, ``--method``), the default first.
METHODS = (MULTIPLE_SHOOTING, PLAIN_SHOOTING)
#: ``compare`` and ``sweep``: ``--method both`` runs every method of :data:`METHODS`.
ALL_METHODS = "both"

#: How multiple shooting solves its NLP (``solver.nlp``): "auto" (Newton, IPOPT only where a path
#: inequality is violated), "rootfinder" (Newton only), "ipopt" (IPOPT always).
NLPS = ("auto", "rootfinder", "ipopt")
#: What solved a subphase, as summary.json reports it: the NLPs' two algorithms and plain shooting's.
ROOTFINDER, IPOPT, BISECTION_SECANT = "rootfinder", "ipopt", "bisection-secant"

#: The stance formulation (``solver.stance``): "monitored" is the paper's (pa follows the hip
#: sinusoid by feedback; a square problem); "tracking" frees pa over the grid and lets IPOPT track
#: the sinusoid under the hip floor (multiple shooting only).
MONITORED, TRACKING = "monitored", "tracking"
STANCES = (MONITORED, TRACKING)

#: What a lock does to the other rates (the stance leg reaching l1, §4.2; the knee at full
#: extension, eq. 5): "momentum" conserves every other generalized momentum, "zero" (the paper's
#: reading) sets only the locked rate to zero.
MOMENTUM, ZERO = "momentum", "zero"
LOCK_RULES = (MOMENTUM, ZERO)

# -- the solver defaults (config.SolverConfig, WalkSpec, make_solver) --------------------------
DEFAULT_METHOD = MULTIPLE_SHOOTING
#: intervals of every subphase grid
DEFAULT_INTERVALS = 20
#: RK4 substeps of each interval
SUBSTEPS = 4
#: the final conditions' largest residual a converged subphase may leave (m, rad)
DEFAULT_TOLERANCE = 1e-9
#: Newton iterations (multiple shooting; IPOPT gets 10x, plain shooting at least 60 shots)
DEFAULT_MAX_ITERATIONS = 50
DEFAULT_NLP = "auto"
DEFAULT_STANCE = MONITORED
DEFAULT_LOCK_RULE = MOMENTUM
