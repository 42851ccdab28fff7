"""walk.bvh's and walk.mot's frames as text in numpy (io/fixed_text.py): the characters of
``"%.{d}f" % value`` for every value, or None where that form does not hold."""
import numpy as np
import pytest

from klaw_ocp.io.fixed_text import fixed_decimals_rows, fixed_decimals_text


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
