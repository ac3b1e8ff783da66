"""JSON for people: floats written without the noise of accumulated rounding error.

A threshold found by bisection is ``0.8549218750000002`` in float64 and a change point summed
from 0.1 s bins is ``10.200000000000001``: the last digits are the error of the arithmetic that
made them, not information. Every JSON document rocas writes for a reader (``report.json``,
``campaign.json``, the ``--json`` output of every command) goes through :func:`dumps`, which
writes each float with :data:`SIGNIFICANT_DIGITS` significant digits (then the shortest repr
that reads back as that value). Twelve digits keep a micrometre over a kilometre and a
nanosecond over an hour, far below any quantity rocas measures, and drop the error of the
last one to four ulps.

Internal state that a resumed analysis reads back (``state.json``, checkpoints) is written
exactly, as it was computed: rounding it would change what a resumed run computes.
"""

from __future__ import annotations

import json
import math
from typing import Any

#: significant digits of every float in a JSON document written for a reader
SIGNIFICANT_DIGITS = 12


def round_float(x: float, digits: int = SIGNIFICANT_DIGITS) -> float:
    """``x`` rounded to ``digits`` significant digits (nan and infinities unchanged)."""
    if not math.isfinite(x) or x == 0.0:
        return x
    return float(f"{x:.{digits}g}")


def rounded(obj: Any, digits: int = SIGNIFICANT_DIGITS) -> Any:
    """``obj`` (a tree of dicts, lists, tuples and scalars) with every float rounded by
    :func:`round_float`; tuples become lists, as JSON writes them; other values are kept."""
    if isinstance(obj, float):
        return round_float(obj, digits)
    if isinstance(obj, dict):
        return {k: rounded(v, digits) for k, v in obj.items()}
    if isinstance(obj, list | tuple):
        return [rounded(v, digits) for v in obj]
    return obj


def dumps(obj: Any, **kwargs: Any) -> str:
    """``json.dumps(rounded(obj), **kwargs)``: the document a reader gets."""
    return json.dumps(rounded(obj), **kwargs)
