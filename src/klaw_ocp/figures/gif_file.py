"""walk.gif's file (:mod:`.animation`): frames streamed into a GIF as they are drawn, on one shared
palette.

A GIF is a header with a global palette and a loop count, then one block per frame: its delay, the
rectangle it covers and its LZW-compressed palette indices. :class:`GifStream` writes the header
when the first frame comes and each frame's block when the next one comes (the last at
:meth:`~GifStream.finish`), so that it holds two frames whatever the walk's length: the frames of a
1000-step walk (7000 of them) took 1.4 GB when Pillow was handed them all at the end. Like
Pillow's own optimised GIFs, a frame covers only the rectangle where it differs from the previous
one, its unchanged pixels there transparent (LZW compresses runs of them), and a frame identical
to the previous one only lengthens its delay. The LZW compression is Pillow's
(:func:`PIL.GifImagePlugin.getdata`); the rest of the format is written here.
"""
from __future__ import annotations

import struct

import numpy as np

#: the palette's size: the most frequent colours of the first frame
PALETTE_COLOURS = 128
_TABLE = 256                     # the global colour table's entries (a power of two >= PALETTE_COLOURS + 1)
TRANSPARENT = _TABLE - 1         # the index of an unchanged pixel (never a palette colour)
_DISPOSAL_KEEP = 1               # each frame is drawn over the previous one (GIF's "do not dispose")


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
        # colour code -> 1 + palette index, 0 for a colour not looked up yet: zeros, so that only the
        # pages of the colours met take memory (a full table of 16 MB did)
        self.lookup = np.zeros(1 << 24, dtype=np.uint8)
        self.lookup[top] = np.arange(1, len(top) + 1)
        padded = np.vstack([self.colours, np.repeat(self.colours[:1], _TABLE - len(top), axis=0)])
        self.table = padded.astype(np.uint8).tobytes()              # GIF's colour table: RGB triples

    @staticmethod
    def _codes(rgba: np.ndarray) -> np.ndarray:
        """(h, w, 4) uint8 -> (h, w) int: R + 256 G + 65536 B (the four bytes read as one number)."""
        return (np.ascontiguousarray(rgba).view("<u4")[..., 0] & 0xFFFFFF).astype(np.intp)

    @staticmethod
    def _rgb(codes: np.ndarray) -> np.ndarray:
        return np.column_stack([codes & 255, (codes >> 8) & 255, (codes >> 16) & 255]).astype(np.int32)

    def indices(self, rgba: np.ndarray) -> np.ndarray:
        """``rgba`` (h, w, 4) uint8 (alpha ignored) as (h, w) uint8 indices of this palette."""
        codes = self._codes(rgba)
        index = self.lookup[codes]
        unseen = index == 0
        if unseen.any():
            new = np.unique(codes[unseen])
            distance = ((self._rgb(new)[:, None, :] - self.colours[None, :, :]) ** 2).sum(axis=2)
            self.lookup[new] = distance.argmin(axis=1) + 1
            index = self.lookup[codes]
        index -= 1
        return index


class GifStream:
    """A looping GIF written into ``handle`` (a binary file) frame by frame, at ``fps`` frames per
    second (a frame's delay is stored in 1/100 s: 1000 / fps ms should be a whole number of 10 ms).
    The palette is taken from the first frame (:class:`Palette`). Call :meth:`add_frame` for every
    frame, then :meth:`finish` once."""

    def __init__(self, handle, fps: float):
        self.handle, self.delay_ms = handle, 1000.0 / fps
        self.palette = None
        self.previous = None             # the last frame's indices (h, w)
        self.pending = None              # the last frame's block, written when the next one differs
        self.frames = 0                  # frames written to the file (after merging identical ones)

    def add_frame(self, rgba: np.ndarray) -> None:
        """The next frame, (h, w, 4) uint8 RGBA (alpha ignored)."""
        if self.palette is None:
            self.palette = Palette(rgba)
            self._header(rgba.shape[1], rgba.shape[0])
        index = self.palette.indices(rgba)
        if self.previous is None:
            self.pending = [index, (0, 0), None, self.delay_ms]
        else:
            changed = index != self.previous
            rows, cols = np.flatnonzero(changed.any(axis=1)), np.flatnonzero(changed.any(axis=0))
            if rows.size == 0:                       # as the previous frame: show that one longer
                self.pending[3] += self.delay_ms
                return
            box = (slice(rows[0], rows[-1] + 1), slice(cols[0], cols[-1] + 1))
            crop = np.where(changed[box], index[box], np.uint8(TRANSPARENT))
            self._write_pending()
            self.pending = [crop, (int(cols[0]), int(rows[0])), TRANSPARENT, self.delay_ms]
        self.previous = index

    def finish(self) -> None:
        """Write the last frame and the GIF's end; the handle stays open (the caller's)."""
        self._write_pending()
        self.handle.write(b";")

    def _header(self, width: int, height: int) -> None:
        size_bits = int(np.log2(_TABLE)) - 1
        self.handle.write(b"GIF89a" + struct.pack("<HHBBB", width, height, 0x80 | 0x70 | size_bits, 0, 0)
                          + self.palette.table
                          # NETSCAPE2.0: loop forever (count 0)
                          + b"!\xff\x0bNETSCAPE2.0\x03\x01" + struct.pack("<H", 0) + b"\x00")

    def _write_pending(self) -> None:
        if self.pending is None:
            return
        from PIL import GifImagePlugin, Image
        index, offset, transparent, delay_ms = self.pending
        params = {"duration": delay_ms, "disposal": _DISPOSAL_KEEP}
        if transparent is not None:
            params["transparency"] = transparent
        image = Image.frombytes("P", (index.shape[1], index.shape[0]), np.ascontiguousarray(index).tobytes())
        # the frame's control block (delay, disposal, transparency), its rectangle and its LZW data,
        # on the global palette
        for chunk in GifImagePlugin.getdata(image, offset=offset, **params):
            self.handle.write(chunk)
        self.frames += 1
        self.pending = None
