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
    """The end of a one-line text that changes every frame (the title's clock). The text's start is
    an ordinary artist, drawn once with the still parts; the end is drawn with the Agg renderer's
    own ``draw_text`` just after it, at the place matplotlib's layout gives the start
    (:meth:`place`): a Text artist lays itself out anew and renders every glyph at each draw,
    which cost three times the clock's own glyphs. The place holds for every end whose characters
    fit within the height and descent of the start (digits after a name)."""

    def __init__(self, start, end: str):
        self.start, self.text, self.where = start, end, None
        self.axes = None

    def get_zorder(self):
        return self.start.get_zorder()

    def set_animated(self, animated: bool) -> None:
        pass                     # the start is still: drawn with the background

    def set_text(self, end: str) -> None:
        self.text = end

    def place(self, renderer) -> None:
        """Lay the start out once and keep where the end begins: the start's own line, moved right
        by the start's advance (the ink width of "|" + start + "|" less that of "||")."""
        where = []

        class Recorder:          # the renderer, but draw_text only records its arguments
            def __getattr__(self, name):
                return getattr(renderer, name)

            def draw_text(self, gc, x, y, s, prop, angle, ismath=False, mtext=None):
                where.append((x, y, prop, angle))
        self.start.draw(Recorder())
        x, y, prop, angle = where[0]

        def width(text):
            return renderer.get_text_width_height_descent(text, prop, False)[0]
        self.where = (x + width(f"|{self.start.get_text()}|") - width("||"), y, prop, angle)

    def draw(self, renderer) -> None:
        if self.where is None:
            self.place(renderer)
        x, y, prop, angle = self.where
        gc = renderer.new_gc()
        gc.set_foreground(self.start.get_color())
        gc.set_alpha(self.start.get_alpha())
        renderer.draw_text(gc, x, y, self.text, prop, angle)
        gc.restore()


class _FastArtist:
    """What :class:`FastLine` and :class:`FastSegments` share: they stand in for their matplotlib
    artist in :class:`Blitter` (its z-order and ``animated`` flag) and draw with one graphics
    context set up from the artist's style."""

    def __init__(self, artist):
        self.artist, self.axes = artist, artist.axes

    def get_zorder(self):
        return self.artist.get_zorder()

    def set_animated(self, animated: bool) -> None:
        self.artist.set_animated(animated)

    @staticmethod
    def _gc(renderer, box, antialiased, linewidth, joinstyle, capstyle, snap, rgba):
        """A graphics context clipped to ``box`` (None: not clipped) with this style (a None join
        or cap style keeps the renderer's)."""
        gc = renderer.new_gc()
        if box is not None:
            gc.set_clip_rectangle(box)
        gc.set_antialiased(antialiased)
        gc.set_linewidth(linewidth)
        if joinstyle is not None:
            gc.set_joinstyle(joinstyle)
        if capstyle is not None:
            gc.set_capstyle(capstyle)
        gc.set_snap(snap)
        gc.set_foreground(rgba, isRGBA=True)
        return gc


class FastLine(_FastArtist):
    """A solid line without markers (a :class:`~matplotlib.lines.Line2D`) drawn straight with the
    renderer's ``draw_path``, in display coordinates, with the line's own style: ``Line2D.draw``
    rebuilds its path, transform and graphics context at every draw, which cost three times the
    drawing itself."""

    @staticmethod
    def fits(artist) -> bool:
        from matplotlib.lines import Line2D
        return (isinstance(artist, Line2D) and artist.get_linestyle() == "-" and artist.get_marker() in ("None", None, "")
                and not artist.get_path_effects() and artist.get_sketch_params() is None)

    def draw(self, renderer) -> None:
        from matplotlib.colors import to_rgba
        from matplotlib.path import Path
        from matplotlib.transforms import IdentityTransform
        line = self.artist
        x, y = line.get_data()
        if len(x) == 0:
            return
        gc = self._gc(renderer, line.get_clip_box() if line.get_clip_on() else None, line.get_antialiased(),
                      line.get_linewidth(), line.get_solid_joinstyle(), line.get_solid_capstyle(), line.get_snap(),
                      to_rgba(line.get_color(), line.get_alpha()))
        xy = np.column_stack([np.asarray(x, float), np.asarray(y, float)])
        renderer.draw_path(gc, Path(line.get_transform().transform(xy)), IdentityTransform())
        gc.restore()


class FastSegments(_FastArtist):
    """A :class:`~matplotlib.collections.LineCollection` of one colour and width (ground ticks,
    footprints) drawn straight with the renderer's ``draw_path``, one call per segment that
    reaches into its clip box (as the collection draws them, so that translucent ones overlap
    alike): ``Collection.draw`` prepares every path, its transform and style at every draw,
    which cost as much as all the lines of a frame."""

    def __init__(self, collection):
        super().__init__(collection)
        self._paths, self._xy = None, None

    @staticmethod
    def fits(artist) -> bool:
        from matplotlib.collections import LineCollection
        return (isinstance(artist, LineCollection) and len(artist.get_colors()) <= 1
                and len(artist.get_linewidths()) == 1 and len(artist.get_linestyles()) == 1
                and artist.get_linestyles()[0][1] is None and not artist.get_path_effects()
                and artist.get_offsets().size == 0)

    def draw(self, renderer) -> None:
        from matplotlib.path import Path
        from matplotlib.transforms import IdentityTransform
        collection = self.artist
        paths = collection.get_paths()
        if paths is not self._paths:                    # new segments (set_segments): read them once
            self._paths = paths
            self._xy = [np.asarray(p.vertices, float) for p in paths]
        if not self._xy or not len(collection.get_colors()):
            return
        transform = collection.get_transform()
        box = collection.get_clip_box() if collection.get_clip_on() else None
        gc = self._gc(renderer, box, bool(collection.get_antialiased()[0]), float(collection.get_linewidths()[0]),
                      collection.get_joinstyle(), collection.get_capstyle(), collection.get_snap(),
                      tuple(collection.get_colors()[0]))
        pad = renderer.points_to_pixels(float(collection.get_linewidths()[0])) + 2
        for xy in self._xy:
            xy = transform.transform(xy)
            if box is not None and (xy[:, 0].max() < box.x0 - pad or xy[:, 0].min() > box.x1 + pad
                                    or xy[:, 1].max() < box.y0 - pad or xy[:, 1].min() > box.y1 + pad):
                continue
            renderer.draw_path(gc, Path(xy), IdentityTransform())
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
        moving = [FastLine(a) if FastLine.fits(a) else FastSegments(a) if FastSegments.fits(a) else a for a in moving]
        drawer = {getattr(m, "artist", m): m for m in moving}
        in_axes = [drawer[a] for ax in fig.axes for a in sorted((a for a in ax.get_children() if a in drawer),
                                                                key=lambda a: a.get_zorder())]
        self.moving = in_axes + sorted((m for m in moving if m.axes is None), key=lambda m: m.get_zorder())
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
