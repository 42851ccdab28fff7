"""Every file of a results folder, named once: the registry that the step-by-step writer
(:mod:`.run_writer`), the folder staging (:mod:`.results_folder`), the commands (``run``,
``plot``, ``compare``, ``sweep``, ``reproduce``) and docs/experiments.md read.

A run's files are :data:`RUN_FILES`, in the order they are written: each a :class:`RunFile` with
its name in the folder, what it holds, and what makes it. A text file is rendered from the run's
:class:`~.run_data.RunData` by its ``renderer``, a ``"module:function"`` imported only when a
file is rendered (:func:`load`): this module imports nothing of the package, so that ``klaw-ocp
run`` reads the names without loading CasADi or matplotlib. Adding a format is its module (a
function of a RunData returning the file's bytes) and one entry here; the plots are listed by
:mod:`klaw_ocp.figures.registry`, one PNG each in ``plots/``.
"""
from __future__ import annotations

from dataclasses import dataclass
from importlib import import_module

#: what makes a file: rendered to bytes from the RunData; written by the command from its config;
#: drawn by klaw_ocp.figures (in the render pool, after the text files)
TEXT, CONFIG, DRAWN = "text", "config", "drawn"


@dataclass(frozen=True)
class RunFile:
    """One file of a run's folder.

    ``key`` names it in code (:func:`klaw_ocp.result_files.render_run`'s keys); ``name`` is its
    path in the folder (``plots/*.png``: one file per plot); ``holds`` what it holds, in a few
    words. ``made_by`` is :data:`TEXT`, :data:`CONFIG` or :data:`DRAWN`; ``renderer`` the
    ``"module:function"`` that makes it (TEXT: ``f(run) -> bytes``; DRAWN: the figures' entry).
    ``body``: written only for a walk with a body to show (a completed step, angles.csv's frames).
    ``option``: the output option that turns it off (``output.plots``, ``output.animation``; ``run
    --no-plots``, ``--no-animation``), None for a file every run writes."""
    key: str
    name: str
    holds: str
    made_by: str
    renderer: str | None = None
    body: bool = False
    option: str | None = None

    @property
    def folder(self) -> str:
        """The subfolder the file is in ("" for the results folder itself)."""
        return self.name.rpartition("/")[0]


RUN_FILES = {f.key: f for f in (
    RunFile("summary", "summary.json", "status, method, body, times, failure, solver messages, and per step its "
            "plan, stance leg, hip reference, subphases (parameters, residual, iterations, solve time)",
            TEXT, "klaw_ocp.result_files.summary_json:summary_file"),
    RunFile("dynamics", "dynamics.csv", "one row per sample: states, hip, the hip sinusoid, every force and torque",
            TEXT, "klaw_ocp.result_files.tables:dynamics_file"),
    RunFile("events", "events.csv", "the foot events of both legs: heel strike, foot flat, heel-off, toe-off",
            TEXT, "klaw_ocp.result_files.tables:events_file"),
    RunFile("angles", "angles.csv", "the body at every frame (output.fps): time, root, the 56 skeleton angles",
            TEXT, "klaw_ocp.result_files.tables:angles_file", body=True),
    RunFile("bvh", "walk.bvh", "the body for animators: the 37-joint skeleton, every frame at output.fps",
            TEXT, "klaw_ocp.result_files.bvh:bvh_file", body=True),
    RunFile("mot", "walk.mot", "the body as OpenSim coordinates (gait2392, gait10dof18musc)",
            TEXT, "klaw_ocp.result_files.opensim:mot_file", body=True),
    RunFile("resolved", "config.resolved.yaml", "the config with --set, --method, --stance, --fps folded in and "
            "every default filled in", CONFIG, "klaw_ocp.config:ExperimentConfig.resolved_yaml"),
    RunFile("animation", "walk.gif", "the body walking, side on and from behind (docs/gif.md)",
            DRAWN, "klaw_ocp.figures.animation:write_animation", body=True, option="animation"),
    RunFile("plots", "plots/*.png", "the plots of klaw_ocp.figures.registry.PLOTS",
            DRAWN, "klaw_ocp.figures.plots:render_plots", option="plots"),
)}

#: the file that makes a folder without the marker one of ``run``'s (written before the marker)
RUN_KEY_FILE = RUN_FILES["summary"].name

# -- the other commands' folders ---------------------------------------------------------------
COMPARISON_CSV, COMPARISON_PNG = "comparison.csv", "comparison.png"
#: compare's folder: each solved run in a run folder of its own under it
COMPARE_RUNS = "runs"
SWEEP_CSV, SWEEP_PNG = "sweep.csv", "sweep.png"
NUMBERS_JSON, PAPER_README = "numbers.json", "README.md"

#: the marker of a folder klaw-ocp wrote (:mod:`.results_folder`)
MARKER = ".klaw-ocp"


def run_file_names(plots: bool = True, animation: bool = True, body: bool = True, resolved: bool = True) -> list:
    """The names (patterns for the plots) a run writes: every file but those its options turn off,
    the body's files only with ``body``, config.resolved.yaml only with ``resolved``."""
    on = {"plots": plots, "animation": animation}
    return [f.name for f in RUN_FILES.values()
            if (f.option is None or on[f.option]) and (body or not f.body) and (resolved or f.made_by != CONFIG)]


def folder_patterns(names) -> tuple:
    """``names`` (``/``-separated fnmatch patterns) with every folder on the way to them."""
    out = []
    for name in names:
        parts = name.split("/")
        out.extend("/".join(parts[:i]) for i in range(1, len(parts)))
        out.append(name)
    return tuple(dict.fromkeys(out))


#: What each command writes into its folder (``/``-separated fnmatch patterns): results_folder
#: accepts a folder holding only these (and its marker) as the command's own.
RUN_FOLDER = folder_patterns(f.name for f in RUN_FILES.values())
COMMAND_FOLDERS = {
    "run": RUN_FOLDER,
    "compare": (COMPARISON_CSV, COMPARISON_PNG, COMPARE_RUNS, f"{COMPARE_RUNS}/*", f"{COMPARE_RUNS}/*/{MARKER}",
                *(f"{COMPARE_RUNS}/*/{p}" for p in RUN_FOLDER)),
    "sweep": (SWEEP_CSV, SWEEP_PNG),
    "reproduce": (PAPER_README, NUMBERS_JSON, COMPARISON_CSV, "*.png"),
}
#: The file that makes a folder without the marker one of the command's.
KEY_FILES = {"run": RUN_KEY_FILE, "compare": COMPARISON_CSV, "sweep": SWEEP_CSV, "reproduce": NUMBERS_JSON}


def load(reference: str):
    """The function a ``"module:function"`` reference names (``function`` may be dotted: a
    class's method), imported now."""
    module, _, name = reference.partition(":")
    target = import_module(module)
    for part in name.split("."):
        target = getattr(target, part)
    return target
