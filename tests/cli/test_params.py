import io
import json

from rocas.cli.console import Env
from rocas.cli.main import main
from rocas.stacks.ads.params import PARAMETERS


def _run(*argv):
    out, err = io.StringIO(), io.StringIO()
    status = main(list(argv), Env(stdout=out, stderr=err))
    return status, out.getvalue(), err.getvalue()


def test_json_lists_every_parameter():
    status, out, _ = _run("params", "--json")
    assert status == 0
    items = json.loads(out)
    assert len(items) == len(PARAMETERS) >= 120
    first = items[0]
    assert set(first) == {"name", "module", "default", "low", "high", "unit", "description"}


def test_module_filter_and_table():
    status, out, _ = _run("params", "--module", "planning")
    assert status == 0
    assert "planning.yield_distance_m" in out and "control.speed_kp" not in out


def test_unknown_module_is_a_usage_error():
    status, _, err = _run("params", "--module", "radar")
    assert status == 2 and "unknown module 'radar'" in err
