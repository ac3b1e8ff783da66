"""Progress on stderr: shown on a terminal for diff and view, never in a pipe or with --json."""

import io
import json

import pytest
from foreign_stack import make_pair

from rocas.cli.console import Env
from rocas.cli.main import main

DESCRIPTION = "Reading both recordings"


class _Terminal(io.StringIO):
    """A captured stream that says it is a terminal."""

    def isatty(self) -> bool:
        return True


@pytest.fixture(scope="module")
def pair(tmp_path_factory):
    return make_pair(tmp_path_factory.mktemp("pair"), deviating="forecaster")


def _run(argv, stderr, delay_s=0.0):
    out = io.StringIO()
    code = main([str(a) for a in argv], env=Env(stdout=out, stderr=stderr,
                                                   progress_delay_s=delay_s))
    return code, out.getvalue(), stderr.getvalue()


def _progress_like(text: str) -> bool:
    return DESCRIPTION in text or "\x1b[" in text or "\r" in text or "Writing the Rerun" in text


def test_diff_shows_progress_on_a_terminal(pair):
    code, out, err = _run(["diff", pair.accident, pair.reference], _Terminal())
    assert code == 0
    assert DESCRIPTION in err
    assert "Initial deviating module" in out


@pytest.mark.parametrize("stderr, flags", [(io.StringIO(), []), (io.StringIO(), ["--json"]),
                                           (_Terminal(), ["--json"])])
def test_diff_writes_nothing_progress_like_when_piped_or_json(pair, stderr, flags):
    code, out, err = _run(["diff", pair.accident, pair.reference, *flags], stderr)
    assert code == 0
    assert not _progress_like(err), err
    if flags:
        assert json.loads(out)["deviating_module"] == "forecaster"


def test_a_short_diff_shows_no_progress_within_the_delay(pair):
    code, _, err = _run(["diff", pair.accident, pair.reference], _Terminal(), delay_s=60.0)
    assert code == 0
    assert not _progress_like(err), err


@pytest.mark.parametrize("terminal", [True, False])
def test_view_progress_only_on_a_terminal(pair, tmp_path, terminal):
    stderr = _Terminal() if terminal else io.StringIO()
    code, _, err = _run(["view", pair.accident, "--rrd", tmp_path / "out.rrd", "--no-viewer"],
                        stderr)
    assert code == 0, err
    assert ("Writing the Rerun recording" in err) is terminal
    if not terminal:
        assert not _progress_like(err), err
