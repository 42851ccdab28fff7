"""The plots of a run (``<results>/plots/``), named once: what ``klaw-ocp run`` and ``plot``
draw, the render pool's tasks (:mod:`.render_pool`), ``reproduce`` and the docs read this list.

Each :class:`Plot` names its file and its figure function as ``"module:function"`` (a function
of a :class:`~klaw_ocp.result_files.RunData` returning a matplotlib Figure), imported only when
the plot is drawn: this module imports neither matplotlib nor the package, so that ``klaw-ocp
run`` reads it before the walk. Adding a plot is its figure function and one entry here.
"""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class Plot:
    """One plot: ``name`` (how code and the pool name it), ``file`` (in ``plots/``), ``figure``
    (``"module:function"`` of a RunData), ``seconds`` (about how long it takes to draw on the
    natural walk, one core: the pool starts the longest first so that the cores finish together)."""
    name: str
    file: str
    figure: str
    seconds: float


_PLOTS = "klaw_ocp.figures.plots"
#: The plots, in the order they are written (docs/experiments.md, "The plots of a run").
PLOTS = {p.name: p for p in (
    Plot("hip_height", "hip_height.png", f"{_PLOTS}:hip_height_figure", 0.14),
    Plot("gait_diagram", "gait_diagram.png", "klaw_ocp.figures.gait_diagram:gait_diagram_figure", 0.15),
    Plot("torques", "torques.png", f"{_PLOTS}:torques_figure", 0.30),
    Plot("states", "states.png", f"{_PLOTS}:states_figure", 0.24),
    Plot("legs", "legs.png", "klaw_ocp.figures.strobe:legs_figure", 0.25),
    Plot("joint_angles", "joint_angles.png", "klaw_ocp.figures.body_plots:joint_angles_figure", 0.32),
    Plot("body", "body.png", "klaw_ocp.figures.body_plots:body_figure", 0.56),
)}

#: walk.gif as a task of the render pool (its file and function are the result files registry's,
#: klaw_ocp.result_files.registry.RUN_FILES["animation"]), and how long it takes to draw
GIF_TASK, GIF_SECONDS = "gif", 1.1


def cost_order() -> tuple:
    """The pool's tasks (every plot and walk.gif) from the slowest to the quickest."""
    seconds = {name: p.seconds for name, p in PLOTS.items()}
    seconds[GIF_TASK] = GIF_SECONDS
    return tuple(sorted(seconds, key=lambda name: -seconds[name]))


def figure_modules() -> list:
    """Every module that draws a plot (the render pool's workers import them once)."""
    return list(dict.fromkeys(p.figure.partition(":")[0] for p in PLOTS.values()))
