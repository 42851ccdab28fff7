"""The pixels of walk.gif (:mod:`.animation`): texts rasterised once and blended into every frame,
and one shared palette for every frame, so that a frame costs one Agg draw.

matplotlib lays out and rasterises every text anew at each draw, which took half the time of a
frame; Pillow's own mapping to a given palette is approximate (white came out 252 grey)."""
from __future__ import annotations

import numpy as np
from matplotlib.animation import PillowWriter

#: texts' font size (points)
FONT = 8
#: the palette's size: the most frequent colours of the first frame
PALETTE_COLOURS = 128
_UNSEEN = 255                    # a colour not looked up yet (palette indices are < PALETTE_COLOURS)


def rasterise(fig, items) -> list:
    """Texts ``items`` [(x_px, y_px, text, style)] (display pixels, y up) rasterised once on a
    transparent figure like ``fig``: for each, (row0, col0, rgb (h, w, 3) float 0-255, alpha
    (h, w, 1) float 0-1) of the patch of pixels it covers (row0, col0 of the patch's top left,
    rows counted from the top)."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure
    from matplotlib.transforms import IdentityTransform
    width_in, _ = fig.get_size_inches()
    lowest = min([0.0] + [y for _, y, _, _ in items])            # a tall layer for labels stacked below
    height_px = int(np.ceil(fig.bbox.height - lowest)) + 4
    layer = Figure(figsize=(width_in, height_px / fig.dpi), dpi=fig.dpi)
    FigureCanvasAgg(layer)
    layer.patch.set_alpha(0.0)
    shift = height_px - fig.bbox.height                          # keeps fig's pixel rows from the top
    texts = [layer.text(x, y + shift, text, transform=IdentityTransform(), **style) for x, y, text, style in items]
    layer.canvas.draw()
    rgba = np.asarray(layer.canvas.buffer_rgba()).astype(float) / 255.0
    height, width = rgba.shape[:2]
    renderer = layer.canvas.get_renderer()
    patches = []
    for text in texts:
        box = text.get_window_extent(renderer)
        r0, r1 = max(0, int(height - box.y1) - 2), min(height, int(np.ceil(height - box.y0)) + 2)
        c0, c1 = max(0, int(box.x0) - 2), min(width, int(np.ceil(box.x1)) + 2)
        patch = rgba[r0:r1, c0:c1]             # buffer_rgba is straight (not premultiplied) alpha
        patches.append((r0, c0, patch[..., :3] * 255.0, patch[..., 3:]))   # rows: as in fig (see shift)
    return patches


def blend_patch(rgb: np.ndarray, patch, row0: int, col0: int, columns=(0, None)) -> None:
    """Draw a patch of :func:`rasterise` over ``rgb`` (h, w, 3) uint8 in place, its top left at
    (row0, col0), only within ``columns`` (first, end)."""
    _, _, colour, alpha = patch
    lo, hi = columns[0], rgb.shape[1] if columns[1] is None else columns[1]
    a, b = max(col0, lo), min(col0 + colour.shape[1], hi)
    if b <= a:
        return
    rows = slice(row0, row0 + colour.shape[0])
    under = rgb[rows, a:b]
    c, al = colour[: under.shape[0], a - col0:b - col0], alpha[: under.shape[0], a - col0:b - col0]
    under[...] = (under * (1.0 - al) + c * al + 0.5).astype(np.uint8)


class StaticText:
    """The texts that never change (panel titles, legend, fixed scales), collected while the figure
    is built, rasterised once (:meth:`freeze`) and blended into every frame's pixels
    (:meth:`blend`): matplotlib lays out and rasterises every text anew at each draw, which took
    half the time of a frame (and a ``figimage`` of them as much again)."""

    def __init__(self):
        self.items = []
        self.patches = []

    def add(self, transform, xy, text: str, **style) -> None:
        self.items.append((transform, xy, text, {"fontsize": FONT, "color": "#333333", **style}))

    def freeze(self, fig) -> None:
        """Rasterise the texts at their positions now (every axes placed and limited)."""
        self.patches = rasterise(fig, [(*transform.transform(xy), text, style)
                                        for transform, xy, text, style in self.items])

    def blend(self, rgb: np.ndarray) -> None:
        for patch in self.patches:
            blend_patch(rgb, patch, patch[0], patch[1])


class MovingLabels:
    """Labels that keep their text and move sideways with a view (the side view's metres): each
    rasterised once, centred on its anchor, and blended at the anchor's pixel column of the frame,
    clipped to the view."""

    def __init__(self, fig, ax, values, texts, y: float, style: dict):
        self.ax, self.values = ax, np.asarray(values, float)
        x_px, y_px = ax.transData.transform((float(ax.get_xlim()[0]), y))
        anchor_x = fig.bbox.width / 2
        # stacked one below the other under the figure, each centred on anchor_x, its top at y_px
        items = [(anchor_x, y_px - 40 * k, text, {"fontsize": FONT - 1, "ha": "center", "va": "top", **style})
                 for k, text in enumerate(texts)]
        self.patches = rasterise(fig, items)
        self.row0 = [p[0] - 40 * k for k, p in enumerate(self.patches)]  # back to y_px's rows
        self.offset = [p[1] - int(round(anchor_x)) for p in self.patches]
        self.x_px = None

    def place(self) -> None:
        """Take the anchors' pixel columns from the view's limits now (after a frame's set_xlim)."""
        self.x_px = self.ax.transData.transform(np.column_stack([self.values, np.zeros_like(self.values)]))[:, 0]
        box = self.ax.bbox
        self.columns = (int(round(box.x0)), int(round(box.x1)))

    def blend(self, rgb: np.ndarray) -> None:
        lo, hi = self.columns
        for k in np.flatnonzero((self.x_px > lo - 60) & (self.x_px < hi + 60)):
            col0 = int(round(self.x_px[k])) + self.offset[k]
            blend_patch(rgb, self.patches[k], self.row0[k], col0, self.columns)


class LiveText:
    """A one-line text whose string changes every frame (the title's clock), drawn with the Agg
    renderer's own ``draw_text`` at the place matplotlib's layout gave it once (:meth:`place`):
    the :class:`~matplotlib.text.Text` artist lays itself out anew at each draw, which cost five
    times the drawing of its glyphs. Its place is the same for every string as long as the
    changing characters fit within the height and the descent of the rest (digits in a title)."""

    def __init__(self, text):
        self.artist, self.text, self.where = text, text.get_text(), None
        self.axes = None

    def get_zorder(self):
        return self.artist.get_zorder()

    def set_animated(self, animated: bool) -> None:
        self.artist.set_animated(animated)

    def set_text(self, text: str) -> None:
        self.text = text

    def place(self, renderer) -> None:
        """Lay the artist out once (with its current string) and keep where its line is drawn."""
        where = []

        class Recorder:          # the renderer, but draw_text only records its arguments
            def __getattr__(self, name):
                return getattr(renderer, name)

            def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
                where.append((x, y, prop, angle))
        self.artist.set_text(self.text)
        self.artist.draw(Recorder())
        self.where = where[0]

    def draw(self, renderer) -> None:
        if self.where is None:
            self.place(renderer)
        x, y, prop, angle = self.where
        gc = renderer.new_gc()
        gc.set_foreground(self.artist.get_color())
        gc.set_alpha(self.artist.get_alpha())
        renderer.draw_text(gc, x, y, self.text, prop, angle)
        gc.restore()


class Blitter:
    """A figure whose still parts are drawn once: ``moving`` artists are left out of that draw
    (``animated``), the ``still`` overlays (:class:`StaticText`) blended into its pixels, and a
    frame is those pixels with the moving artists drawn over them, in their order (matplotlib's
    blitting). A full draw of the figure per frame cost three times as much: the axes, the still
    artists and the figure itself were drawn again each time."""

    def __init__(self, fig, moving: list, still: list):
        # matplotlib's order: the axes in turn, in each its artists by zorder (ties in the order
        # they were added), then the figure's own (the title)
        chosen = set(moving)
        in_axes = [a for ax in fig.axes for a in sorted((a for a in ax.get_children() if a in chosen),
                                                         key=lambda a: a.get_zorder())]
        self.moving = in_axes + sorted((a for a in moving if a.axes is None), key=lambda a: a.get_zorder())
        for artist in self.moving:
            artist.set_animated(True)
        fig.canvas.draw()
        self.renderer = fig.canvas.get_renderer()
        self.buffer = np.asarray(self.renderer.buffer_rgba())       # the canvas's own pixels (a view)
        for overlay in still:
            overlay.blend(self.buffer[..., :3])
        self.background = self.buffer.copy()

    def pixels(self, overlays: list) -> np.ndarray:
        """The still pixels, the moving artists drawn over them, then ``overlays`` blended: (h, w,
        4) uint8 RGBA, a copy."""
        self.buffer[...] = self.background
        for artist in self.moving:
            artist.draw(self.renderer)
        rgba = self.buffer.copy()
        for overlay in overlays:
            overlay.blend(rgba[..., :3])
        return rgba


class PaletteWriter(PillowWriter):
    """matplotlib's PillowWriter (Pillow writes the GIF: no ffmpeg), given each frame's pixels
    (:meth:`Animation.pixels`: one draw, no savefig) as palette images (:class:`Palette`)."""

    def setup(self, fig, outfile, dpi=None):
        super().setup(fig, outfile, dpi=dpi)
        self._palette = None

    def add_frame(self, rgba: np.ndarray) -> None:
        if self._palette is None:
            self._palette = Palette(rgba)
        self._frames.append(self._palette.image(rgba))

    def grab_frame(self, **savefig_kwargs):
        raise NotImplementedError("use add_frame(Animation.pixels())")


class Palette:
    """One palette for every frame: the PALETTE_COLOURS most frequent colours of the first frame,
    exactly (the background, the ground and the lines keep their colours); any other colour (an
    antialiased edge) takes its nearest, without dithering (flat colours compress well and nothing
    flickers). Pillow's own mapping to a given palette is approximate (white came out 252 grey),
    so the colours are looked up here, each new one once."""

    def __init__(self, rgba: np.ndarray):
        values, counts = np.unique(self._codes(rgba), return_counts=True)
        top = values[np.argsort(-counts, kind="stable")[:PALETTE_COLOURS]]
        self.colours = self._rgb(top)
        self.lookup = np.full(1 << 24, _UNSEEN, dtype=np.uint8)      # colour code -> palette index (16 MB)
        self.lookup[top] = np.arange(len(top))
        padded = np.vstack([self.colours, np.repeat(self.colours[:1], 256 - len(top), axis=0)])
        self.flat = padded.astype(np.uint8).ravel().tolist()

    @staticmethod
    def _codes(rgba: np.ndarray) -> np.ndarray:
        """(h, w, 4) uint8 -> (h, w) int: R + 256 G + 65536 B (the four bytes read as one number)."""
        return (np.ascontiguousarray(rgba).view("<u4")[..., 0] & 0xFFFFFF).astype(np.intp)

    @staticmethod
    def _rgb(codes: np.ndarray) -> np.ndarray:
        return np.column_stack([codes & 255, (codes >> 8) & 255, (codes >> 16) & 255]).astype(np.int32)

    def image(self, rgba: np.ndarray):
        """``rgba`` (h, w, 4) uint8 (alpha ignored) as a "P" image of this palette."""
        from PIL import Image
        codes = self._codes(rgba)
        index = self.lookup[codes]
        unseen = index == _UNSEEN
        if unseen.any():
            new = np.unique(codes[unseen])
            distance = ((self._rgb(new)[:, None, :] - self.colours[None, :, :]) ** 2).sum(axis=2)
            self.lookup[new] = distance.argmin(axis=1)
            index = self.lookup[codes]
        image = Image.fromarray(index, "P")
        image.putpalette(self.flat)
        return image
