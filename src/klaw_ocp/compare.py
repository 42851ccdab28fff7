"""Comparing finished runs: the same walk in both solver modes, or two different walks.

Pure functions over :class:`~klaw_ocp.result_files.run_data.RunData` (a finished run read from memory or
from a results folder); nothing here solves, reads YAML or imports a solver. The first run is the
reference; every other run is compared with it.

- :func:`comparison_rows` (and :func:`comparison_csv`): one row per step, subphase and run, in that
  order, with the torque-profile parameters of each subphase BVP (section 3 of the paper: the
  parameters the bisection+secant or multiple-shooting solver finds), the solver's residual,
  iterations, wall time, NLP and fallbacks, and each parameter's difference to the first run's
  same step (by step index) and subphase (by name).
- :func:`comparison_stats` (and :func:`comparison_table`): the largest hip-height and joint-angle
  differences over the common time range, the largest parameter difference per subphase name,
  and each run's total solve time and iterations.

Time grids: two runs of the same configuration (e.g. ``multiple-shooting`` against
``plain-shooting``) sample the same times, and their columns are subtracted sample by sample.
Otherwise the other run is linearly interpolated onto the first run's times inside the
overlapping time range. At a heel strike a run has two samples at the same time (end of one step,
start of the next); the interpolation uses the later one. The joint angles are relabelled at heel
strike (the swing leg becomes the stance leg), so between runs whose heel strikes fall at
different times the largest angle difference is dominated by that jump.
"""
from __future__ import annotations

import csv
import io
import math
from collections import Counter

import numpy as np

#: the subphase BVPs of a step, in the order a step solves them
SUBPHASES = ("stance", "swing1", "swing2", "swing3")
#: the generalized coordinates compared sample by sample, with their units
ANGLE_COLUMNS = {"w": "m", "theta1": "rad", "theta2": "rad", "theta3": "rad", "theta4": "rad"}


# -- labels and parameters ---------------------------------------------------------------------------
def unique_labels(runs) -> list[str]:
    """Each run's :attr:`~klaw_ocp.result_files.run_data.RunData.label`; a label that occurs more than once
    gets ``#2``, ``#3``, ... on its second, third, ... occurrence."""
    seen: Counter = Counter()
    labels = []
    for run in runs:
        seen[run.label] += 1
        labels.append(run.label if seen[run.label] == 1 else f"{run.label} #{seen[run.label]}")
    return labels


def _parameter_units(runs) -> dict:
    """Parameter name -> unit, in order of first appearance over runs, steps and subphases."""
    units: dict = {}
    for run in runs:
        for step in run.steps:
            for sub in step["subphases"]:
                for name in sub["parameters"]:
                    units.setdefault(name, (sub.get("units") or {}).get(name) or "-")
    return units


def parameter_header(name: str, unit: str) -> str:
    """``F_theta1_magnitude [N m]``: a parameter's column header."""
    return f"{name} [{unit}]"


def _subphase_index(run) -> dict:
    """(step index, subphase name) -> the summary entry of that subphase."""
    return {(int(step["index"]), sub["name"]): sub for step in run.steps for sub in step["subphases"]}


def _subphase_order(name: str) -> int:
    return SUBPHASES.index(name) if name in SUBPHASES else len(SUBPHASES)


# -- rows --------------------------------------------------------------------------------------------
def comparison_rows(runs) -> list[dict]:
    """One row per step, subphase and run, ordered by (step index, subphase, run).

    Columns: ``run`` (:func:`unique_labels`), ``step``, ``subphase``; every parameter as
    ``name [unit]`` (None where the subphase has no such parameter); ``residual``,
    ``iterations``, ``solve_s`` (the subphase's wall time), ``nlp``, ``fallbacks`` (joined with
    ``"; "``); then ``d_name [unit]``: this run's parameter minus the first run's at the same step
    index and subphase name (None for the first run, and where either side is missing). Every
    row has every column; None is an empty cell in :func:`comparison_csv`.
    """
    if not runs:
        return []
    units = _parameter_units(runs)
    labels = unique_labels(runs)
    indexed = [_subphase_index(run) for run in runs]
    keys = sorted({key for index in indexed for key in index}, key=lambda k: (k[0], _subphase_order(k[1]), k[1]))
    reference = indexed[0]
    rows = []
    for step, name in keys:
        for i, (label, index) in enumerate(zip(labels, indexed)):
            sub = index.get((step, name))
            if sub is None:
                continue
            params = sub["parameters"]
            row = {"run": label, "step": step, "subphase": name}
            row.update({parameter_header(p, u): _number(params.get(p)) for p, u in units.items()})
            row.update(residual=_number(sub.get("residual")), iterations=sub.get("iterations"),
                       solve_s=_number(sub.get("wall_s")), nlp=sub.get("nlp"),
                       fallbacks="; ".join(str(f) for f in sub.get("fallbacks") or []))
            ref = reference.get((step, name)) if i > 0 else None
            for p, u in units.items():
                mine, theirs = params.get(p), (ref or {}).get("parameters", {}).get(p)
                diff = None if mine is None or theirs is None else float(mine) - float(theirs)
                row["d_" + parameter_header(p, u)] = diff
            rows.append(row)
    return rows


def _number(value):
    return None if value is None else float(value)


def comparison_csv(rows: list[dict]) -> str:
    """``rows`` as CSV text; the header is the union of the rows' columns, in order of first
    appearance; None (and a missing column) is an empty cell; floats keep full precision."""
    columns = list(dict.fromkeys(c for row in rows for c in row))
    buffer = io.StringIO()
    writer = csv.writer(buffer, lineterminator="\n")
    writer.writerow(columns)
    for row in rows:
        writer.writerow(["" if row.get(c) is None else repr(row[c]) if isinstance(row[c], float) else row[c]
                         for c in columns])
    return buffer.getvalue()


# -- time series -------------------------------------------------------------------------------------
def _nanmax_abs(values: np.ndarray) -> tuple[float, int | None]:
    """(largest finite |value|, its index); (nan, None) if there is none."""
    values = np.abs(np.asarray(values, dtype=float))
    finite = np.isfinite(values)
    if not finite.any():
        return math.nan, None
    index = int(np.flatnonzero(finite)[np.argmax(values[finite])])
    return float(values[index]), index


def _strictly_increasing(t: np.ndarray, values: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Drop the earlier of repeated times (a heel strike's two samples): np.interp needs increasing xp."""
    keep = np.append(np.diff(t) > 0, True)
    return t[keep], values[keep]


def aligned_differences(first, other, columns) -> dict:
    """``other`` minus ``first`` for each column on ``first``'s times.

    Returns ``{"grid": "identical" | "interpolated" | "no overlap", "t": times, "range_s":
    (start, end), "note": a sentence, column: differences}``. Identical time grids are
    subtracted sample by sample; otherwise ``other`` is linearly interpolated onto ``first``'s
    times inside the overlap of the two time ranges (NaN in either run stays NaN)."""
    ta, tb = np.asarray(first.table["t"], float), np.asarray(other.table["t"], float)
    if ta.shape == tb.shape and ta.size and np.array_equal(ta, tb):
        out = {"grid": "identical", "t": ta, "range_s": (float(ta[0]), float(ta[-1])),
               "note": "identical time grids, differences sample by sample"}
        out.update({c: np.asarray(other.table[c], float) - np.asarray(first.table[c], float) for c in columns})
        return out
    start = max(ta.min(), tb.min()) if ta.size and tb.size else math.nan
    end = min(ta.max(), tb.max()) if ta.size and tb.size else math.nan
    if not (end > start):
        out = {"grid": "no overlap", "t": ta[:0], "range_s": (start, end),
               "note": "the time ranges do not overlap; nothing compared"}
        out.update({c: ta[:0] for c in columns})
        return out
    inside = (ta >= start) & (ta <= end)
    t = ta[inside]
    out = {"grid": "interpolated", "t": t, "range_s": (float(start), float(end)),
           "note": f"different time grids: the other run interpolated linearly onto the first run's "
                   f"times over {start:.3f}-{end:.3f} s"}
    for c in columns:
        xp, fp = _strictly_increasing(tb, np.asarray(other.table[c], float))
        out[c] = np.interp(t, xp, fp) - np.asarray(first.table[c], float)[inside]
    return out


def _largest(diffs: dict, column: str, unit: str) -> dict:
    value, index = _nanmax_abs(diffs[column])
    return {"value": value, "unit": unit, "t_s": None if index is None else float(diffs["t"][index])}


# -- statistics --------------------------------------------------------------------------------------
def _largest_parameter_differences(rows: list[dict], label: str) -> dict:
    """Subphase name -> {"value", "parameter", "unit", "step"}: the largest |d_parameter| of one run."""
    best: dict = {}
    for row in rows:
        if row["run"] != label:
            continue
        for column, diff in row.items():
            if not column.startswith("d_") or diff is None or not math.isfinite(diff):
                continue
            entry = best.get(row["subphase"])
            if entry is None or abs(diff) > entry["value"]:
                name, unit = column[2:].rsplit(" [", 1)
                best[row["subphase"]] = {"value": abs(diff), "parameter": name, "unit": unit[:-1],
                                         "step": row["step"]}
    return {name: best.get(name) for name in sorted(best, key=_subphase_order)}


def _totals(run) -> dict:
    subs = [sub for step in run.steps for sub in step["subphases"]]
    return {"solve_s": float(sum(float(s.get("wall_s") or 0.0) for s in subs)),
            "iterations": int(sum(int(s.get("iterations") or 0) for s in subs)),
            "steps": len(run.steps)}


def comparison_stats(runs) -> dict:
    """How every run differs from the first, and what each run cost.

    Returns ``{"reference": first label, "runs": [entry per run]}``; each entry has ``label``,
    ``method``, ``steps``, ``solve_s`` (sum of the subphases' wall time), ``iterations``; and,
    for every run but the first (None for the first): ``grid`` (identical / interpolated / no
    overlap), ``grid_note``, ``range_s`` (the compared time range), ``hip_y`` ({"value": largest
    |hip_y difference| in m, "unit", "t_s": where}), ``angles`` (w, theta1 ... theta4, the same
    shape), ``parameters`` (subphase name -> {"value": largest |parameter difference|,
    "parameter", "unit", "step"}, over the steps both runs have), ``matched`` / ``unmatched``
    (subphases of this run with / without a counterpart in the first run). Values are NaN where
    nothing could be compared.
    """
    if not runs:
        return {"reference": None, "runs": []}
    labels = unique_labels(runs)
    rows = comparison_rows(runs)
    reference = _subphase_index(runs[0])
    entries = []
    for i, (run, label) in enumerate(zip(runs, labels)):
        entry = {"label": label, "method": run.method, **_totals(run)}
        if i == 0:
            entry.update(grid=None, grid_note="the reference run", range_s=None, hip_y=None, angles=None,
                         parameters=None, matched=None, unmatched=None)
        else:
            diffs = aligned_differences(runs[0], run, ["hip_y", *ANGLE_COLUMNS])
            keys = set(_subphase_index(run))
            entry.update(grid=diffs["grid"], grid_note=diffs["note"], range_s=diffs["range_s"],
                         hip_y=_largest(diffs, "hip_y", "m"),
                         angles={c: _largest(diffs, c, u) for c, u in ANGLE_COLUMNS.items()},
                         parameters=_largest_parameter_differences(rows, label),
                         matched=len(keys & set(reference)), unmatched=len(keys - set(reference)))
        entries.append(entry)
    return {"reference": labels[0], "runs": entries}


# -- the stdout table --------------------------------------------------------------------------------
def _g(value, unit: str = "") -> str:
    if value is None:
        return "-"
    if isinstance(value, float) and not math.isfinite(value):
        return "n/a"
    return f"{value:.3g}" + (f" {unit}" if unit else "")


def comparison_table(stats: dict) -> str:
    """A short aligned plain-text table of :func:`comparison_stats`: runs numbered 1, 2, ... in
    columns (run 1 the reference), the largest differences to run 1 in rows, then each run's
    solve time and iterations."""
    entries = stats["runs"]
    if not entries:
        return "no runs to compare\n"
    lines = [f"run {i + 1}: {e['label']}" for i, e in enumerate(entries)]
    for i, e in enumerate(entries[1:], start=2):
        lines.append(f"run {i} vs run 1: {e['grid_note']}"
                     + (f"; {e['unmatched']} subphases without a match in run 1" if e["unmatched"] else ""))
    # a cell is (value, note): values right-aligned, notes left-aligned after them
    table = [[("", ""), *[(f"run {i + 1}", "") for i in range(len(entries))]]]

    def diff_row(title, pick):
        table.append([(title, ""), ("(reference)", ""), *[pick(e) for e in entries[1:]]])

    diff_row("max |Δ hip height|", lambda e: (_g(e["hip_y"]["value"], "m"), ""))
    for column, unit in ANGLE_COLUMNS.items():
        diff_row(f"max |Δ {column}|", lambda e, c=column, u=unit: (_g(e["angles"][c]["value"], u), ""))
    names = list(dict.fromkeys(n for e in entries[1:] for n in e["parameters"]))
    for name in names:
        def pick(e, n=name):
            best = e["parameters"].get(n)
            return ("-", "") if best is None else (
                _g(best["value"], best["unit"]), f" ({best['parameter']}, step {best['step']})")
        diff_row(f"max |Δ parameter| {name}", pick)
    table.append([("steps", ""), *[(str(e["steps"]), "") for e in entries]])
    table.append([("solve time (sum)", ""), *[(_g(e["solve_s"], "s"), "") for e in entries]])
    table.append([("iterations (sum)", ""), *[(str(e["iterations"]), "") for e in entries]])
    widths = [(max(len(r[j][0]) for r in table), max(len(r[j][1]) for r in table)) for j in range(len(table[0]))]
    body = ["  ".join((value.ljust(wv) if j == 0 else value.rjust(wv)) + note.ljust(wn)
                      for j, ((value, note), (wv, wn)) in enumerate(zip(r, widths))).rstrip() for r in table]
    return "\n".join(lines + [""] + body) + "\n"
