"""The external-process adapter: the LAV-like stack run as a separate program gives the same
recording and outcome as in-process, batches run as several processes, results are cached."""

import dataclasses
import sys
from pathlib import Path

import pytest

from rocas.errors import UsageError
from rocas.recording.reader import open_recording
from rocas.scenarios.catalog import entry
from rocas.stacks.external import ExternalStack
from rocas.stacks.registry import get_stack
from rocas.stacks.rollout import rollout

STACK_FILE = Path(__file__).with_name("lav-process.toml")


def _stack(tmp_path):
    ext = ExternalStack.from_file(STACK_FILE, tmp_path / "cache")
    return dataclasses.replace(ext, command=(sys.executable, *ext.command[1:]))


def _messages(path):
    return [(m.channel.topic, m.log_time_ns, m.data) for m in open_recording(str(path)).messages()]


@pytest.mark.slow
def test_the_external_process_gives_what_the_stack_gives_in_process(tmp_path):
    ext = _stack(tmp_path)
    assert {p.full_name for p in ext.parameters} == {
        p.full_name for p in get_stack("lav").parameters}
    s = dataclasses.replace(entry("A9").scenario, duration_s=3.0)
    params = {"brake.brake_threshold": 0.5}
    first = ext.run(s, params, 4)
    inproc = rollout(get_stack("lav"), s, params, 4, output=tmp_path / "in.mcap")
    assert not first.cached and first.outcome == inproc.outcomes[0]
    assert _messages(first.recording) == _messages(tmp_path / "in.mcap")
    again = ext.run(s, params, 4)
    assert again.cached and again.recording == first.recording
    batch = ext.run_batch([s, s], [params, None], [4, 5], processes=2)
    assert batch[0].cached and not batch[1].cached
    assert batch[1].outcome == rollout(get_stack("lav"), s, None, 5).outcomes[0]


def test_a_failing_command_is_reported_in_one_line(tmp_path):
    ext = dataclasses.replace(_stack(tmp_path), command=(sys.executable, "-c",
                                                         "import sys; sys.exit('boom')"))
    s = dataclasses.replace(entry("A9").scenario, duration_s=0.5)
    with pytest.raises(UsageError, match="exited 1: boom"):
        ext.run(s)
