"""walk.bvh's and walk.mot's frames as text in numpy (io/fixed_text.py): the characters of
``"%.{d}f" % value`` for every value, or None where that form does not hold."""
import numpy as np
import pytest

from klaw_ocp.io.fixed_text import fixed_decimals_rows, fixed_decimals_text, shortest_repr_slots, slots_text, text_slots


def _percent_format(rounded, decimals, separator):
    row = separator.join([f"%.{decimals}f"] * rounded.shape[1])
    return "".join(row % tuple(v) + "\n" for v in rounded.tolist())


@pytest.mark.parametrize("decimals, separator", [(9, " "), (10, "\t"), (1, ","), (2, " "), (3, " "), (4, " ")])
def test_the_text_is_the_percent_format_of_every_value(decimals, separator):
    rng = np.random.default_rng(decimals)
    for trial in range(200):
        shape = (int(rng.integers(1, 12)), int(rng.integers(1, 15)))
        values = rng.normal(0.0, 10.0 ** rng.uniform(-12, 5), shape)
        if trial % 2:   # halfway cases and their neighbours, zeros of both signs
            values = (np.round(values * 10 ** decimals) + rng.choice([0.0, 0.5, -0.5, 0.4999999], shape)) / 10 ** decimals
            values.flat[0], values.flat[-1] = 0.0, -0.0
        rounded = np.round(values, decimals) + 0.0
        text = fixed_decimals_text(rounded, decimals, separator)
        if text is not None:
            assert text == _percent_format(rounded, decimals, separator)


def test_values_the_exact_form_cannot_take_are_left_to_the_percent_format():
    assert fixed_decimals_text(np.array([[1.0, np.nan]]), 9, " ") is None
    assert fixed_decimals_text(np.array([[1.0, 1e6]]), 9, " ") is None          # 1e15 > 2**49
    assert fixed_decimals_text(np.array([[1.0, 2e6]]), 2, " ") is None          # seven digits
    assert fixed_decimals_text(np.array([[123456.5, -999999.25]]), 2, " ") == "123456.50 -999999.25\n"


def test_the_writers_rows_round_first_and_fall_back_to_the_percent_format():
    values = np.array([[-1e-12, 0.1234567891234], [2.5, -3.0]])
    assert fixed_decimals_rows(values, 9, " ") == "0.000000000 0.123456789\n2.500000000 -3.000000000\n"
    large = np.array([[1e7, -0.5], [np.inf, 1.0]])       # beyond the numpy form: "%" per row
    assert fixed_decimals_rows(large, 9, "\t") == _percent_format(np.round(large, 9) + 0.0, 9, "\t")
    assert fixed_decimals_rows(np.zeros((0, 3)), 9, " ") == ""
def _repr_rows(values):
    return "".join(repr(v) + "\n" for v in values.tolist())


def test_shortest_repr_slots_are_repr_of_every_value():
    # dynamics.csv's exact floats (io/fixed_text.py's argument): random bit patterns, values of
    # every scale, short decimals and their neighbours, powers of ten and two, specials
    rng = np.random.default_rng(5)
    n = 20000
    bits = rng.integers(0, 2 ** 63, n, dtype=np.uint64) | (rng.integers(0, 2, n, dtype=np.uint64) << np.uint64(63))
    short = np.concatenate([np.round(rng.normal(0, 100, n // 10), d) for d in range(10)])
    cut = np.array([float(f"{x:.{p}g}") for x, p in zip(rng.normal(0, 10.0 ** rng.uniform(-12, 16, n // 4)),
                                                        rng.integers(1, 18, n // 4))])
    samples = [bits.view(np.float64), rng.normal(0, 10.0 ** rng.uniform(-14, 17, n)), short,
               np.nextafter(short, np.inf), cut, np.nextafter(cut, -np.inf),
               10.0 ** rng.integers(-15, 18, 2000) * rng.choice([1, -1, 2, 5, 0.5, 1.5, 9.999999999999999], 2000),
               np.ldexp(1.0, rng.integers(-60, 60, 500)), rng.integers(-10 ** 6, 10 ** 6, n).astype(float),
               np.array([0.0, -0.0, np.nan, -np.nan, np.inf, -np.inf, 1e-320, 5e-324, 1.7976931348623157e308,
                         1e-11, 1e15, 0.0001, 1e-05, 1e16, 9999999999999998.0, 0.1, 1 / 3])]
    for values in samples:
        assert slots_text([shortest_repr_slots(values)]) == _repr_rows(values)


def test_slots_text_joins_cells_and_texts_into_rows():
    values = np.array([[1.5, -0.0, np.nan], [2e-07, 123456.0, 0.25]])
    cells = shortest_repr_slots(values).reshape(2, 3, -1)
    text = slots_text([cells[:, :1], text_slots(["a", "bcdef"]), cells[:, 1:]])
    assert text == "1.5,a,-0.0,nan\n2e-07,bcdef,123456.0,0.25\n"
