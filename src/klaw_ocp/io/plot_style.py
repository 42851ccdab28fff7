"""What every plot of klaw_ocp shares, defined once: the subphase colours, the figure size and
resolution, the paper's symbols with units, and rendering a figure to PNG bytes.

Colours are the Okabe-Ito palette (colour-blind safe), one per subphase of a step (stance, the
hind leg's double support, swing1, swing2, swing3), so a reader learns them once. Figures are
drawn on the Agg canvas directly (``matplotlib.figure.Figure``, no pyplot and no global backend),
which needs no display and is safe in worker processes.
"""
from __future__ import annotations

import io

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


def new_figure(width_in: float, height_in: float) -> Figure:
    """An Agg figure with the shared font size and a constrained layout (nothing clipped)."""
    fig = Figure(figsize=(width_in, height_in), dpi=DPI, layout="constrained")
    FigureCanvasAgg(fig)
    return fig


def style_axes(ax) -> None:
    ax.tick_params(labelsize=FONT_PT)
    ax.xaxis.label.set_size(FONT_PT + 1)
    ax.yaxis.label.set_size(FONT_PT + 1)
    ax.title.set_size(FONT_PT + 1)
    ax.grid(True, lw=0.4, alpha=0.4)


def png_bytes(fig: Figure) -> bytes:
    """The figure as a PNG at :data:`DPI`."""
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=DPI)
    return buffer.getvalue()
