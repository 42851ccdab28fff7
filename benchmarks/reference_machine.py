"""docs/performance.md's reference machine, for the benchmarks' estimates of their numbers there.

The machines these benchmarks run on are shared and their CPUs differ: the same code ran the
acceptance grid twice as slowly on 2026-12-07 as on the days before. The median stance solve of
the natural walk (multiple shooting, monitored stance) is compiled C and numpy bookkeeping, like
the rest of the pipeline, so its ratio to the reference machine's says how much slower a machine is
for this work. A benchmark prints that ratio beside its measurements, and an estimate scaled by it
clearly marked as one; the measurements stay the numbers.
"""
#: The reference machine's median stance solve, ms. It was 0.5 ms with the code of session 29;
#: session 30 made the solve itself faster (Newton's chord step, -O2 kernels): four alternating
#: pairs of the old and new code on one machine put the new solve at 0.70-0.78 of the old (median
#: 0.755), so 0.5 ms x 0.755 with this code.
REFERENCE_STANCE_SOLVE_MS = 0.38


def slower_than_reference(stance_solve_ms: float) -> float:
    """How many times slower than the reference machine a machine whose median stance solve of
    the natural walk takes ``stance_solve_ms`` is."""
    return stance_solve_ms / REFERENCE_STANCE_SOLVE_MS
