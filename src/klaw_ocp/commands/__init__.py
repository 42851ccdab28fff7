"""The subcommands of ``klaw-ocp``, one module each: ``configure(parser)`` sets up its arguments
(with an example in the description) and ``handle(args) -> exit code`` runs it. :mod:`klaw_ocp.cli`
registers them and turns every :class:`klaw_ocp.errors.KlawError` into one line and exit 2.

Exit codes: 0 done, 1 a walk did not converge (what was solved is still written), 2 bad input.
"""
EXIT_OK = 0
EXIT_NOT_CONVERGED = 1
EXIT_USAGE = 2
PROG = "klaw-ocp"
