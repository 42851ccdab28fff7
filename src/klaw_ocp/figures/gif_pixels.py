"""The pixels of walk.gif (:mod:`.animation`): the still parts drawn once, texts rasterised once and
blended into every frame, the moving lines drawn straight with the Agg renderer, so that a frame
costs one Agg draw of what moves (:class:`Blitter`). The frames go to the file as they are drawn
(:mod:`.gif_file`).

matplotlib lays out and rasterises every text anew at each draw, which took half the time of a
frame."""
from __future__ import annotations

import numpy as np

#: texts' font size (points)
FONT = 8


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
    rgba = np.asarray(layer.canvas.buffer_rgba())       # uint8: only the patches become floats
    height, width = rgba.shape[:2]
    renderer = layer.canvas.get_renderer()
    patches = []
    for text in texts:
        box = text.get_window_extent(renderer)
        r0, r1 = max(0, int(height - box.y1) - 2), min(height, int(np.ceil(height - box.y0)) + 2)
        c0, c1 = max(0, int(box.x0) - 2), min(width, int(np.ceil(box.x1)) + 2)
        patch = rgba[r0:r1, c0:c1].astype(float) / 255.0   # buffer_rgba is straight (not premultiplied) alpha
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
    """Labels that keep their text and move sideways with a view (the side view's metres), shown as
    an axis shows its tick labels: whole while the anchor (its tick) is in the view and the label
    in the figure, not at all once it has left (a label cut at the view's edge, "4 r" for "4 m",
    read as another mark). Each is rasterised once, centred on its anchor, :data:`BLOCK` labels at
    a time as the view reaches them, and dropped when the view has left them: a long walk has one
    a metre, and rasterising all of them at once took a layer 40 px high a label (640 MB of floats
    for a 1000-step walk)."""

    BLOCK = 16

    def __init__(self, fig, ax, values, texts, y: float, style: dict):
        self.fig, self.ax = fig, ax
        self.values, self.texts = np.asarray(values, float), list(texts)
        self.y_px = float(ax.transData.transform((float(ax.get_xlim()[0]), y))[1])
        self.anchor_x = fig.bbox.width / 2
        self.style = {"fontsize": FONT - 1, "ha": "center", "va": "top", **style}
        self.blocks = {}                 # block -> [(row0, column offset, patch)] of its labels
        self.x_px = None

    def _block(self, block: int) -> list:
        if block not in self.blocks:
            texts = self.texts[block * self.BLOCK:(block + 1) * self.BLOCK]
            # stacked one below the other under the figure, each centred on anchor_x, its top at y_px
            patches = rasterise(self.fig, [(self.anchor_x, self.y_px - 40 * k, text, self.style)
                                           for k, text in enumerate(texts)])
            self.blocks[block] = [(p[0] - 40 * k, p[1] - int(round(self.anchor_x)), p)   # back to y_px's rows
                                  for k, p in enumerate(patches)]
        return self.blocks[block]

    def place(self) -> None:
        """Take the anchors' pixel columns from the view's limits now (after a frame's set_xlim)."""
        self.x_px = self.ax.transData.transform(np.column_stack([self.values, np.zeros_like(self.values)]))[:, 0]
        self.columns = (self.ax.bbox.x0, self.ax.bbox.x1)

    def shown(self) -> np.ndarray:
        """The labels whose anchor is in the view now (:meth:`place`)."""
        return np.flatnonzero((self.x_px >= self.columns[0]) & (self.x_px <= self.columns[1]))

    def blend(self, rgb: np.ndarray) -> None:
        shown = self.shown()
        for block in set(self.blocks) - set((shown // self.BLOCK).tolist()):
            del self.blocks[block]                 # the view has left them
        for k in shown:
            row0, offset, patch = self._block(k // self.BLOCK)[k % self.BLOCK]
            col0 = int(round(self.x_px[k])) + offset
            if col0 >= 0 and col0 + patch[2].shape[1] <= rgb.shape[1]:
                blend_patch(rgb, patch, row0, col0)


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
