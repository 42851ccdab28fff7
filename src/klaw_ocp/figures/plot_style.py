"""What every plot of klaw_ocp shares, defined once: the subphase colours, the figure size and
resolution, the paper's symbols with units, which steps of a long walk the plots draw (its first
and last, on axes side by side: :func:`drawn_steps`, :func:`axes_rows`), and rendering a figure
to PNG bytes.

Colours are the Okabe-Ito palette (colour-blind safe), one per subphase of a step (stance, the
hind leg's double support, swing1, swing2, swing3), so a reader learns them once. Figures are
drawn on the Agg canvas directly (``matplotlib.figure.Figure``, no pyplot and no global backend),
which needs no display and is safe in worker processes. :func:`png_bytes` draws a figure once and
hands the pixels to Pillow: ``savefig`` would draw it twice.
"""
from __future__ import annotations

import io

import numpy as np
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure

DPI = 150
FONT_PT = 9
#: Okabe-Ito
SUBPHASE_COLOURS = {
    "stance": "#0072B2",          # blue
    "double_support": "#999999",  # grey
    "swing1": "#E69F00",          # orange
    "swing2": "#D55E00",          # vermillion
    "swing3": "#009E73",          # bluish green
}
SUBPHASE_LABELS = {"stance": "stance", "double_support": "double support", "swing1": "swing1",
                   "swing2": "swing2", "swing3": "swing3"}
#: the two legs (step 0's stance leg is the right one)
LEG_COLOURS = {"right": "#0072B2", "left": "#CC79A7"}
#: a second, third, ... compared run
RUN_COLOURS = ("#0072B2", "#D55E00", "#009E73", "#CC79A7", "#E69F00", "#56B4E9", "#F0E442", "#000000")
ACCENT = "#000000"

#: dynamics.csv column -> axis label with the paper's symbol and unit
SYMBOLS = {
    "w": "w (m)", "theta1": "θ1 (rad)", "theta2": "θ2 (rad)", "theta3": "θ3 (rad)", "theta4": "θ4 (rad)",
    "hip_y": "hip height (m)", "hip_x": "hip x (m)",
    "F_w": "F_w (N)", "pa": "pa (m)", "F_theta1": "F_θ1 (N·m)", "F_theta2": "F_θ2 (N·m)",
    "F_theta3": "F_θ3 (N·m)", "F_theta4": "F_θ4 (N·m)",
}
FORCE_COLUMNS = ("F_w", "pa", "F_theta1", "F_theta2", "F_theta3", "F_theta4")
#: zlib level of the PNGs (:func:`encode_png`): about as small as Pillow's default 6, a third faster
PNG_COMPRESS_LEVEL = 3
#: The plots that draw every step (hip_height, gait_diagram, torques, states and legs.png) draw a
#: walk of more than MAX_DRAWN_STEPS steps in two parts, its first FIRST_STEPS steps and its last
#: LAST_STEPS, and say so (:func:`drawn_steps`): a whole 1000-step walk left 1.5 px a step in the
#: time plots, and legs.png's strobe of it was 93 panels, a 48 723-pixel-high image of 1.1 GB.
MAX_DRAWN_STEPS = 60
FIRST_STEPS, LAST_STEPS = 40, 10
PART_GAP_IN = 0.3            # between the two parts' axes (inches)


def new_figure(width_in: float, height_in: float, layout: str | None = "constrained") -> Figure:
    """An Agg figure with the shared font size and a constrained layout (nothing clipped);
    ``layout=None`` for a figure whose axes are placed in inches (:func:`add_axes_in`)."""
    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout=layout)
    FigureCanvasAgg(fig)
    return fig


def add_axes_in(fig: Figure, left: float, bottom: float, width: float, height: float, **kwargs):
    """An axes placed in inches from the figure's lower-left corner. The run plots place their
    axes so (margins sized for their labels at :data:`FONT_PT`): a constrained layout costs about
    as much as drawing the figure again."""
    w, h = fig.get_size_inches()
    return fig.add_axes((left / w, bottom / h, width / w, height / h), **kwargs)


def axes_column(fig: Figure, heights: list, left: float, right: float, top: float, gaps, sharex: bool = True) -> list:
    """Axes stacked from ``top`` inches below the figure's top edge downwards, ``heights`` and
    ``gaps`` (one number, or one per gap) in inches, ``left``/``right`` margins in inches."""
    w, h = fig.get_size_inches()
    gaps = [gaps] * (len(heights) - 1) if isinstance(gaps, (int, float)) else list(gaps)
    axes, y = [], h - top
    for i, height in enumerate(heights):
        y -= height
        share = axes[0] if sharex and axes else None
        axes.append(add_axes_in(fig, left, y, w - left - right, height, sharex=share))
        if i < len(gaps):
            y -= gaps[i]
    if sharex:
        for ax in axes[:-1]:
            ax.tick_params(labelbottom=False)
    return axes


def drawn_steps(n_steps: int) -> list[tuple[int, int]]:
    """(first, last) step of each part of a walk of ``n_steps`` that the plots draw: the whole walk,
    or for more than MAX_DRAWN_STEPS its first FIRST_STEPS and its last LAST_STEPS steps."""
    if n_steps <= MAX_DRAWN_STEPS:
        return [(0, n_steps - 1)]
    return [(0, FIRST_STEPS - 1), (n_steps - LAST_STEPS, n_steps - 1)]


def drawn_note(n_steps: int) -> str:
    """What a figure says of the steps it draws (:func:`drawn_steps`): "" for the whole walk."""
    parts = drawn_steps(n_steps)
    if len(parts) == 1:
        return ""
    (a0, b0), (a1, b1) = parts
    return (f"a long walk: steps {a0}–{b0} and {a1}–{b1} of {n_steps} drawn, {b0 + 1}–{a1 - 1} left out "
            f"(dynamics.csv has every step)")


def part_spans(run) -> list[tuple[float, float]]:
    """(t0, t1), walk time, of each part of ``run`` the plots draw (:func:`drawn_steps`): (0, the
    walk's last heel strike) for the whole walk."""
    steps = run.steps
    parts = drawn_steps(len(steps))
    end = steps[-1]["t_start_s"] + steps[-1]["t_step_s"]
    if len(parts) == 1:
        return [(0.0, end)]
    return [(steps[a]["t_start_s"], steps[b]["t_start_s"] + steps[b]["t_step_s"]) for a, b in parts]


def axes_rows(fig: Figure, heights: list, left: float, right: float, top: float, gaps, spans: list,
              split=None, sharex: bool = True) -> list[list]:
    """:func:`axes_column` with each row (those in ``split``, default all) cut into one axes per
    part of the walk, side by side PART_GAP_IN apart, as wide as the parts' ``spans`` (t0, t1) are
    long (at least 1.2 in); the parts of a row share its y axis (labelled on the first), those of
    a column their x axis (``sharex``). Returns the rows, each the list of its axes; one span:
    :func:`axes_column`'s axes, one a row."""
    column = axes_column(fig, heights, left, right, top, gaps, sharex)
    rows = [[ax] for ax in column]
    if len(spans) == 1:
        return rows
    w, h = fig.get_size_inches()
    room = w - left - right - PART_GAP_IN * (len(spans) - 1)
    lengths = np.array([t1 - t0 for t0, t1 in spans], float)
    widths = np.maximum(room * lengths / lengths.sum(), 1.2)
    widths[0] = room - widths[1:].sum()
    split = range(len(heights)) if split is None else split
    first = None                               # the first split row: its parts share x with the others'
    for r in split:
        ax = column[r]
        box = ax.get_position()
        ax.set_position((box.x0, box.y0, widths[0] / w, box.height))
        x = left + widths[0] + PART_GAP_IN
        for k, width in enumerate(widths[1:], start=1):
            share = first[k] if sharex and first is not None else None
            part = add_axes_in(fig, x, box.y0 * h, width, box.height * h, sharey=ax, sharex=share)
            part.tick_params(labelleft=False, labelbottom=not (sharex and r < len(heights) - 1))
            rows[r].append(part)
            x += width + PART_GAP_IN
        first = first or rows[r]
    return rows


def mark_breaks(parts: list) -> None:
    """The broken axis between consecutive ``parts`` (axes side by side): the facing spines hidden
    and a short slanted stroke at each end of the break."""
    style = {"marker": [(-1, -1.5), (1, 1.5)], "markersize": 7, "ls": "none", "color": "#000000", "mec": "#000000",
             "mew": 0.9, "clip_on": False}
    for left, right in zip(parts, parts[1:]):
        left.spines["right"].set_visible(False)
        right.spines["left"].set_visible(False)
        right.tick_params(left=False)
        left.plot([1, 1], [0, 1], transform=left.transAxes, **style)
        right.plot([0, 0], [0, 1], transform=right.transAxes, **style)


def style_axes(ax) -> None:
    ax.tick_params(labelsize=FONT_PT)
    ax.xaxis.label.set_size(FONT_PT + 1)
    ax.yaxis.label.set_size(FONT_PT + 1)
    ax.title.set_size(FONT_PT + 1)
    ax.grid(True, lw=0.4, alpha=0.4)


def encode_png(pixels: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 array as a PNG at :data:`DPI` (:func:`_png`)."""
    from PIL import Image
    return _png(Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8), "RGB"))


def _png(image) -> bytes:
    """A Pillow image as a PNG at :data:`DPI`, written by Pillow (not matplotlib's own PNG writer)
    at zlib level :data:`PNG_COMPRESS_LEVEL`: the files are as small as at Pillow's default level 6
    (plots are mostly flat colour) and take a third less time to write."""
    buffer = io.BytesIO()
    image.save(buffer, format="png", compress_level=PNG_COMPRESS_LEVEL, dpi=(DPI, DPI))
    return buffer.getvalue()


def png_bytes(fig: Figure) -> bytes:
    """The figure as a PNG at :data:`DPI`, drawn once on its Agg canvas (the layout engine, if
    any, runs inside that draw; ``savefig`` would draw the figure twice, a layout pass and the
    image), its pixels handed to Pillow without a copy of their own in between (a long walk's
    strobe, 2037 × 2790 pixels, peaked 17 MB higher with one)."""
    from PIL import Image
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    dpi = fig.dpi
    try:
        fig.dpi = DPI
        canvas.draw()
        rgba = canvas.buffer_rgba()
        image = Image.frombuffer("RGBA", (rgba.shape[1], rgba.shape[0]), rgba, "raw", "RGBA", 0, 1).convert("RGB")
    finally:
        fig.dpi = dpi
    return _png(image)
