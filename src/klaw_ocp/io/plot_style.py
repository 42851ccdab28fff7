"""What every plot of klaw_ocp shares, defined once: the subphase colours, the figure size and
resolution, the paper's symbols with units, and rendering a figure to PNG bytes.

Colours are the Okabe-Ito palette (colour-blind safe), one per subphase of a step (stance, the
hind leg's double support, swing1, swing2, swing3), so a reader learns them once. Figures are
drawn on the Agg canvas directly (``matplotlib.figure.Figure``, no pyplot and no global backend),
which needs no display and is safe in worker processes. :func:`png_bytes` draws a figure once and
hands the pixels to Pillow (:func:`encode_png`): ``savefig`` would draw it twice.
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


def style_axes(ax) -> None:
    ax.tick_params(labelsize=FONT_PT)
    ax.xaxis.label.set_size(FONT_PT + 1)
    ax.yaxis.label.set_size(FONT_PT + 1)
    ax.title.set_size(FONT_PT + 1)
    ax.grid(True, lw=0.4, alpha=0.4)


def figure_pixels(fig: Figure) -> np.ndarray:
    """The figure drawn once on its Agg canvas at :data:`DPI` (the layout engine, if any, runs
    inside that draw), as an (h, w, 3) uint8 array."""
    canvas = fig.canvas if isinstance(fig.canvas, FigureCanvasAgg) else FigureCanvasAgg(fig)
    dpi = fig.dpi
    try:
        fig.dpi = DPI
        canvas.draw()
        return np.array(np.asarray(canvas.buffer_rgba())[..., :3])
    finally:
        fig.dpi = dpi


def encode_png(pixels: np.ndarray) -> bytes:
    """An (h, w, 3) uint8 array as a PNG at :data:`DPI`, written by Pillow (matplotlib's own PNG
    writer) at zlib level :data:`PNG_COMPRESS_LEVEL`: the files are as small as at Pillow's
    default level 6 (plots are mostly flat colour) and take a third less time to write."""
    from PIL import Image
    buffer = io.BytesIO()
    Image.fromarray(np.ascontiguousarray(pixels, dtype=np.uint8), "RGB").save(
        buffer, format="png", compress_level=PNG_COMPRESS_LEVEL, dpi=(DPI, DPI))
    return buffer.getvalue()


def png_bytes(fig: Figure) -> bytes:
    """The figure as a PNG at :data:`DPI`: :func:`figure_pixels` then :func:`encode_png`.
    (``savefig`` would draw the figure twice, a layout pass and the image.)"""
    return encode_png(figure_pixels(fig))
