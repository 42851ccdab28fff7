"""The subcommands of ``klaw-ocp``, one module each: ``configure(parser)`` sets up its arguments
(with an example in the description) and ``handle(args) -> exit code`` runs it. :mod:`klaw_ocp.cli`
registers them and turns every :class:`klaw_ocp.errors.KlawError` into one line and exit 2.

Exit codes (docs/experiments.md): 0 done; 2 bad input (nothing solved, nothing written); 3 a walk
did not converge (what was solved is still written); 74 the results could not be written (a full
disk, a permission lost, a folder removed: what was written is kept, sysexits' EX_IOERR); 130
interrupted with Ctrl-C, 143 with SIGTERM (what was completed is kept; 128 + the signal's number,
as a shell reports a process the signal ended).
"""
EXIT_OK = 0
EXIT_USAGE = 2
EXIT_SOLVER_FAILED = 3
EXIT_WRITE_FAILED = 74
EXIT_INTERRUPTED = 130
EXIT_TERMINATED = 143
PROG = "klaw-ocp"
