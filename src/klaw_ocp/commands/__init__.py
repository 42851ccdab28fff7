"""The subcommands of ``klaw-ocp``, one module each: ``configure(parser)`` sets up its arguments
(with an example in the description) and ``handle(args) -> exit code`` runs it. :mod:`klaw_ocp.cli`
registers them and turns every :class:`klaw_ocp.errors.KlawError` into one line and exit 2.

Exit codes: 0 done; 2 bad input (nothing solved, nothing written); 3 a walk did not converge
(what was solved is still written, docs/experiments.md); 130 interrupted with Ctrl-C (likewise).
"""
EXIT_OK = 0
EXIT_USAGE = 2
EXIT_SOLVER_FAILED = 3
EXIT_INTERRUPTED = 130
PROG = "klaw-ocp"
