"""Tables of numbers as text with a fixed number of decimals, built in numpy: the same characters
as ``"%.{d}f" % value`` for every value, without a Python format per value.

walk.bvh (171 channels) and walk.mot write every frame's values with a fixed number of decimals;
``%``-formatting them, one row at a time, was most of those files' time (a float's fixed-point
text goes through Python's correctly rounded dtoa, and the formatting machinery runs per value).
Here each value rounded to ``d`` decimals is an integer count k of 10⁻ᵈ, and its text is k's
digits with the decimal point put in: the digits come out of numpy's integer arithmetic for all
values at once, into one byte per character.

Why the characters are the same: the callers round first (``np.round(values, d) + 0.0``), so a
value v is the double nearest to k·10⁻ᵈ, k = rint(v·10ᵈ). While |v|·10ᵈ < 2⁴⁹ both the product's
rounding (< 0.25) and the distance of v from k·10⁻ᵈ (half an ulp of v, < 0.07·10⁻ᵈ) are too small
to reach another k or another d-decimal text, so ``"%.{d}f" % v`` is k's digits. Larger or
non-finite values return None; :func:`fixed_decimals_rows`, which the writers call, then formats
them with ``%`` one row at a time.
"""
from __future__ import annotations

import numpy as np

#: |value| * 10**decimals below this keeps k exact (see the module docstring)
_EXACT_LIMIT = 2.0 ** 49


def _packed(texts) -> np.ndarray:
    """Texts of up to four ASCII characters as uint32 in memory order (zero bytes after them)."""
    raw = np.zeros((len(texts), 4), np.uint8)
    for n, text in enumerate(texts):
        raw[n, :len(text)] = list(text.encode())
    return raw.view("<u4").ravel()


# a value's text in 4-byte slots, zero bytes where it has no character (removed at the end):
#: the sign's byte, then 0 .. 999 right-aligned with no leading zeros (zero bytes before it)
_WHOLE = _packed([f"\0{n:\0>3d}" for n in range(1000)])
#: the same, 0 .. 999 with leading zeros (the last three digits of a larger whole part)
_WHOLE_LOW = _packed([f"\0{n:03d}" for n in range(1000)])
#: three decimals (a group inside the fraction)
_THREE = _packed([f"{n:03d}" for n in range(1000)])
#: the point and the fraction's first one, two or three decimals
_FIRST = {lead: _packed(["." + f"{n:0{lead}d}" for n in range(10 ** lead)]) for lead in (1, 2, 3)}


def fixed_decimals_text(rounded: np.ndarray, decimals: int, separator: str) -> str | None:
    """The rows of ``rounded`` (n, c), already rounded to ``decimals`` and free of -0.0, as
    ``separator.join("%.{decimals}f" % v for v in row)`` each, every row ending in a newline;
    None where a value is not finite, too large for this exact form or has more than six digits
    before the point."""
    rounded = np.asarray(rounded, float)
    if rounded.ndim != 2 or rounded.size == 0 or decimals < 1 or len(separator) != 1:
        return None
    scale = 10 ** decimals
    magnitude = np.abs(rounded)
    if not (np.isfinite(magnitude).all() and magnitude.max() * scale < _EXACT_LIMIT):
        return None
    k = np.rint(rounded * scale).astype(np.int64)
    whole, fraction = np.divmod(np.abs(k), scale)
    if whole.max() >= 10 ** 6:
        return None
    lead = decimals - 3 * ((decimals - 1) // 3)        # the first group's decimals (1 to 3)
    groups = (decimals - 1) // 3                      # the groups of three decimals after the first
    # the separator goes into the last slot's free fourth byte: a slot of its own after ".ddd"
    slots = np.zeros(k.shape + (3 + max(groups, 1),), "<u4")
    sign = np.where(k < 0, ord("-"), 0).astype("<u4")   # the first byte of the first slot
    high = whole >= 1000
    slots[..., 0] = np.where(high, np.take(_WHOLE, whole // 1000 % 1000), 0) | sign
    slots[..., 1] = np.where(high, np.take(_WHOLE_LOW, whole % 1000), np.take(_WHOLE, whole % 1000))
    slots[..., 2] = np.take(_FIRST[lead], fraction // 10 ** (decimals - lead))
    for g, low in enumerate(range(decimals - lead - 3, -1, -3)):
        slots[..., 3 + g] = np.take(_THREE, fraction // 10 ** low % 1000)
    ends = np.full(k.shape, ord(separator), "<u4")
    ends[:, -1] = ord("\n")
    # the separator in the last slot's free fourth byte (little-endian: the highest)
    slots[..., -1] |= ends << 24
    return slots.tobytes().translate(None, b"\0").decode("ascii")     # bytes' C loop drops the zeros


def fixed_decimals_rows(values, decimals: int, separator: str) -> str:
    """The rows of ``values`` (n, c) as text: each value rounded to ``decimals`` and written as
    ``"%.{decimals}f"``, joined by ``separator``, every row ending in a newline ("" for no rows).
    Rounded first and + 0.0, so that a value a hair below zero is written 0, not -0; the numpy
    form of :func:`fixed_decimals_text` where it holds, else a ``%`` format per row (a value too
    large for it, or not finite)."""
    rounded = np.round(np.asarray(values, float), decimals) + 0.0
    if not len(rounded):
        return ""
    text = fixed_decimals_text(rounded, decimals, separator)
    if text is None:
        row = separator.join([f"%.{decimals}f"] * rounded.shape[1])
        text = "\n".join(row % tuple(v) for v in rounded.tolist()) + "\n"
    return text
