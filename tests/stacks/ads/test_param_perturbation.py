"""Every ADS parameter is read: perturbed alone, it changes some module's output somewhere.

Scenarios are tried in order; each one is only asked about the parameters no earlier scenario
has shown to matter. A parameter counts as read when setting it to its lower or its upper bound
changes the fingerprint of some module's published output over the run.
"""

import numpy as np

from rocas.rollout import simulate_batch
from rocas.scenarios import load_example
from rocas.stacks.ads.params import MODULES as MODULE_ORDER
from rocas.stacks.ads.params import PARAMETERS

CASES = (
    ("junction_straight", {}),
    ("wet_truck_turn", {}),
    ("left_turn_oncoming", {}),
    ("foggy_crossing", {}),
    ("junction_straight", {"prediction.cyclist_cut_in_lateral_m": 5.0}),
    ("left_turn_oncoming", {"control.lateral_controller": 1.0}),
    ("junction_straight", {"perception.glare_sun_altitude_deg": 60.0}),  # sun in the camera
    # a longer overlap horizon makes the ego yield to the van and then weigh the car
    ("left_turn_oncoming", {"planning.overlap_check_horizon_s": 8.0}),
    ("left_turn_oncoming", {"planning.overtake_time_buffer_s": 5.0}),  # waits at a standstill
)


def _changed(scenario_name: str, base: dict[str, float], names: list[str]) -> dict[str, str]:
    params = [base]
    for n in names:
        p = PARAMETERS[n]
        params += [{**base, n: p.low}, {**base, n: p.high}]
    res = simulate_batch(load_example(scenario_name), params=params, track_outputs=True)
    d = res.digests
    diff = (d[1:] != d[:1]).reshape(len(names), 2, len(MODULE_ORDER)).any(axis=1)
    return {n: ",".join(m for m, c in zip(MODULE_ORDER, row, strict=True) if c)
            for n, row in zip(names, diff, strict=True) if row.any()}


def test_every_parameter_changes_some_module_output():
    remaining = list(PARAMETERS)
    shown: dict[str, str] = {}
    for name, base in CASES:
        if not remaining:
            break
        found = _changed(name, base, remaining)
        shown.update(found)
        remaining = [n for n in remaining if n not in found]
    assert not remaining, f"parameters with no observable effect: {remaining}"
    # the effect is found in the module that owns the parameter or downstream of it
    assert all(mods for mods in shown.values())
    assert np.all([isinstance(v, str) for v in shown.values()])
