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

# -- shortest reprs -------------------------------------------------------------------------------
# dynamics.csv writes every float as ``repr``: the shortest text that reads back as the same
# double, the closest to it among those. Python's dtoa costs about a microsecond a value, and the
# natural walk has 29 000. Here repr's digits come out of numpy for all values at once:
#
# - y = |v|·10ᵏ, scaled into [10¹⁶, 10¹⁷), is one rounded product of exact numbers in x87's long
#   double (64-bit significand; 10ᵏ is exact for k <= 27), so |y - exact| < 2⁻⁷·⁵. Its integer
#   part T and fraction f are exact; the candidates of 17, 16 and 15 significant digits are T, T
#   and T rounded by f at the units, tens and hundreds, wrong only where the rounding is within
#   that error of a half (those take ``repr``).
# - A candidate reads back as v iff it is less than half an ulp of v from v: its distance from y
#   is exact, half an ulp times 10ᵏ rounded once; too close to call takes ``repr``.
# - Why the first of 15, 16, 17 digits that reads back is repr's: an interval of one ulp holds at
#   most one 15-digit decimal (they are further apart), so a shorter text that reads back is the
#   15-digit one with its zeros dropped; of 16 or 17 digits repr takes the closest that reads back,
#   the correctly rounded one whenever any does, the interval being symmetric about v. It is not
#   at powers of two (half as wide below): those take ``repr``, as do non-finite values and |v|
#   outside [1e-11, 1e15). tests/test_fixed_text.py holds it to ``repr`` on millions of doubles.

_LONG = np.longdouble
#: the argument above holds for one correctly rounded product in x87's 80-bit (63 fraction bits)
#: or IEEE quad (112) long double; elsewhere (a 64-bit long double, ppc64le's double-double) repr
SHORTEST_EXACT = np.finfo(_LONG).nmant in (63, 112)
_POW_LONG = np.cumprod(np.r_[_LONG(1), np.full(27, 10, _LONG)])      # 10**0 .. 10**27, exact
_POW_FLOAT = 10.0 ** np.arange(29)
_POW_INT = np.array([10 ** k for k in range(20)], np.uint64)
_U = list(_POW_INT)      # the same powers as numpy scalars: a list lookup is cheaper than the array's
#: |y - exact| < 2**-7.5, with room: closer than this to a rounding's half or an interval's end
#: is too close to call
_MARGIN = 2.0 ** -6


def _slot_table(texts, slots: int) -> np.ndarray:
    """Texts of up to 4 * ``slots`` ASCII characters as rows of uint32 slots (zero-padded)."""
    raw = np.zeros((len(texts), 4 * slots), np.uint8)
    for n, text in enumerate(texts):
        raw[n, :len(text)] = list(text.encode())
    return raw.view("<u4")


#: the sign and, before digits after the point, "0." and zeros: by minus * 5 + (0, or 1 + zeros)
_PREFIX = _slot_table([sign + ("" if lead == 0 else "0." + "0" * (lead - 1)) for sign in ("", "-")
                       for lead in range(5)], 2)
#: two digits: by pair + 100 * (digits shown 0-2 + 3 * (0, or a point after the first or second))
_PAIR = _slot_table([f"{pair:02d}"[:shown][:dot] + "." + f"{pair:02d}"[dot:shown] if 0 < dot <= shown
                     else f"{pair:02d}"[:shown]
                     for dot in range(3) for shown in range(3) for pair in range(100)], 1).ravel()
#: after the digits: none; zeros and ".0" (index 1 + zeros); an exponent (index 20 + exponent + 99)
_SUFFIX = _slot_table([""] + ["0" * zeros + ".0" for zeros in range(19)] + [f"e{e:+03d}" for e in range(-99, 100)], 5)


_PREFIX_LENGTH, _SUFFIX_LENGTH = ((table.view(np.uint8) != 0).sum(axis=1) for table in (_PREFIX, _SUFFIX))


def _slots_needed(lengths: np.ndarray, index: np.ndarray) -> int:
    """The slots the longest of the texts ``index`` picks needs (fewer zero bytes to drop)."""
    return max(1, -(-int(lengths[index].max(initial=0)) // 4))


def _shortest_digits(values: np.ndarray):
    """repr's digits of each value as (digits, count, decpt): value = 0.d1d2..·10^decpt, without
    the digits' trailing zeros; and where the argument above holds (elsewhere: rubbish)."""
    magnitude = np.abs(values)
    mantissa, exponent2 = np.frexp(magnitude)
    fast = np.isfinite(magnitude) & (magnitude >= 1e-11) & (magnitude < 1e15) & (mantissa != 0.5)
    safe = np.where(fast, magnitude, 1.0)
    k = 16 - np.floor(np.log10(safe)).astype(np.int64)
    guess = safe * _POW_FLOAT[k]
    k = np.clip(k + (guess < 1e16) - (guess >= 1e17), 0, 27)   # log10's floor may be one off
    y = safe.astype(_LONG) * _POW_LONG[k]
    whole = y.astype(np.uint64)
    f = (y - whole.astype(_LONG)).astype(float)                  # exact
    fast &= (whole >= _U[16]) & (whole < _POW_INT[17])
    half_ulp = np.ldexp(_POW_FLOAT[k], exponent2 - 54)
    tens, hundreds = whole // _U[1], whole // _U[2]
    digits, count, found = whole, np.full(len(values), 17), np.zeros(len(values), bool)
    for base, unit, p in ((hundreds, 100.0, 15), (tens, 10.0, 16), (whole, 1.0, 17)):
        below = (whole - base * _U[17 - p]).astype(float) + f   # y less the candidate rounded down
        up = below > unit / 2
        distance = np.abs(below - unit * up) - half_ulp
        unsure = (np.abs(below - unit / 2) <= _MARGIN) | (np.abs(distance) <= _MARGIN)
        take = ~found & (distance < 0)
        fast &= found | ~unsure
        digits = np.where(take, base + up.astype(np.uint64), digits)
        count = np.where(take, p, count)
        found |= take
    fast &= found
    carried = digits >= _POW_INT[count]                           # rounded up to 10^p
    digits = np.where(carried, digits // _U[1], digits)
    decpt = 17 - k + carried
    for step in (8, 4, 2, 1):                                    # trailing zeros, by halves
        shorter = digits // _U[step]
        zeros = (count > step) & (shorter * _U[step] == digits)
        digits = np.where(zeros, shorter, digits)
        count = count - step * zeros
    return digits, count, decpt, fast


def shortest_repr_slots(values) -> np.ndarray:
    """``repr(float(v))`` of each value as rows of 4-byte slots (n, s) of ASCII, zero bytes where
    a text has no character (:func:`slots_text` joins them)."""
    values = np.asarray(values, float).ravel()
    if not SHORTEST_EXACT:
        return text_slots([repr(v) for v in values.tolist()])
    digits, count, decpt, fast = _shortest_digits(values)
    zero = values == 0.0
    digits, count, decpt = np.where(zero, np.uint64(0), digits), np.where(zero, 1, count), np.where(zero, 1, decpt)
    fast |= zero
    scientific = (decpt <= -4) | (decpt > 16)
    leading = ~scientific & (decpt <= 0)                         # 0.00ddd
    prefix = np.where(fast, np.signbit(values) * 5 + np.where(leading, 1 - decpt, 0), 0)
    prefix = np.take(_PREFIX[:, :_slots_needed(_PREFIX_LENGTH, prefix)], prefix, axis=0)
    point = np.where(scientific, 0, decpt - 1)                   # the digit the point follows
    point = np.where(leading | (point + 1 >= count), -9, point)
    left = digits * _POW_INT[17 - count]                         # 17 digits, left-aligned
    pairs = int(count[fast].max() + 1) // 2 if fast.any() else 1
    columns, before = [prefix], np.uint64(0)
    for i in range(pairs):
        scaled = left // _U[15 - 2 * i] if 2 * i <= 15 else left * _U[2 * i - 15]
        pair = (scaled - before * _U[2]).astype(np.int64)
        before = scaled
        shown = np.clip(count - 2 * i, 0, 2)
        dot = point - 2 * i + 1
        dot = np.where((dot == 1) | (dot == 2), dot, 0)
        columns.append(np.take(_PAIR, pair + 100 * (shown + 3 * dot))[:, None])
    suffix = np.where(scientific, 118 + decpt, np.where(~leading & (decpt >= count), 1 + decpt - count, 0))
    suffix = np.where(fast, suffix, 0)
    columns.append(np.take(_SUFFIX[:, :_slots_needed(_SUFFIX_LENGTH, suffix)], suffix, axis=0))
    slots = np.concatenate(columns, axis=1)
    slow = np.flatnonzero(~fast)
    if len(slow):                                                # the rest by repr, a few percent
        texts = text_slots([repr(v) for v in values[slow].tolist()])
        slots = _widened(slots, texts.shape[1])
        slots[slow] = _widened(texts, slots.shape[1])
    return slots


def text_slots(texts: list) -> np.ndarray:
    """ASCII ``texts`` as rows of 4-byte slots (n, s), as :func:`shortest_repr_slots`; each
    distinct text packed once (a column of step numbers or subphase names has few)."""
    codes: dict = {}
    index = np.array([codes.setdefault(text, len(codes)) for text in texts], np.intp)
    width = max(1, -(-max(map(len, codes), default=0) // 4))
    return _slot_table(list(codes), width)[index]


def _widened(slots: np.ndarray, width: int) -> np.ndarray:
    return np.pad(slots, ((0, 0), (0, width - slots.shape[1]))) if width > slots.shape[1] else slots


def slots_text(columns: list, separator: str = ",") -> str:
    """The rows of ``columns`` joined by ``separator``, each row ending in a newline; a column is
    an (n, s) array of slots, or (n, c, s) for c cells in a row."""
    parts = []
    for column in columns:
        cells = column.reshape(len(column), -1, column.shape[-1])
        ends = np.full(cells.shape[:2] + (1,), ord(separator), "<u4")
        parts.append(np.concatenate([cells, ends], axis=2).reshape(len(column), -1))
    parts[-1][:, -1] = ord("\n")
    return np.concatenate(parts, axis=1).tobytes().translate(None, b"\0").decode("ascii")
