"""JSON for readers: floats without accumulated rounding error, the rest untouched."""

import json
import math

from rocas._json import SIGNIFICANT_DIGITS, dumps, round_float, rounded


def test_accumulated_error_is_dropped_and_real_digits_are_kept():
    assert round_float(0.1 + 0.2) == 0.3
    assert round_float(0.30470000000000003) == 0.3047
    assert round_float(0.8549218750000002) == 0.854921875
    assert round_float(10.200000000000001) == 10.2
    assert round_float(4.656612873077393e-10) == 4.65661287308e-10
    assert round_float(123456.789012345678) == 123456.789012
    assert round_float(-1.2895490044394697) == -1.28954900444
    assert round_float(0.0) == 0.0 and round_float(-0.0) == 0.0
    assert math.isnan(round_float(math.nan)) and round_float(math.inf) == math.inf


def test_a_rounded_value_is_within_half_a_unit_of_its_twelfth_digit():
    for x in (math.pi, math.e * 1e7, 1 / 3, 2 / 3 * 1e-5, 1e300 / 7):
        unit = 10 ** (math.floor(math.log10(abs(x))) - SIGNIFICANT_DIGITS + 1)
        assert abs(round_float(x) - x) <= 0.5 * unit * (1 + 1e-9)


def test_trees_are_rounded_and_other_values_kept():
    tree = {"a": [0.1 + 0.2, (1, "x", True, None)], "b": {"c": 10.200000000000001, "d": 7}}
    assert rounded(tree) == {"a": [0.3, [1, "x", True, None]], "b": {"c": 10.2, "d": 7}}
    text = dumps(tree, indent=1)
    assert "0.30000000000000004" not in text and json.loads(text)["b"]["c"] == 10.2
