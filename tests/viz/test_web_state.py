"""Reading the web viewer's state and a .rrd's layout (rocas.viz.web_state): the decoder and the
comparison the browser test relies on, without a browser."""

import rerun.blueprint as rrb

from rocas.viz.stream import rrd_recording
from rocas.viz.web_state import ViewerState, blueprint_views, decode_viewer_state, layout_problem


def _msg(*fields):
    out = b""
    for number, value in fields:
        out += bytes([number << 3 | 2, len(value)]) + value
    return out


def test_the_state_decoder_reads_recordings_selection_and_views():
    view = _msg((1, b"v1"), (2, b"2D"), (3, b"Scene"), (4, b"/world"))
    rec = _msg((1, b"r-1"), (4, b"about:recording"))
    state = _msg((1, b"about:recording"), (2, b"r-1"), (3, rec), (4, b"rerun+http://x"), (5, view))
    state += bytes([5 << 3 | 0, 1])  # a varint field the reader skips
    assert decode_viewer_state(state) == ViewerState("r-1", ("r-1",), {"v1": "Scene"})


def _rrd_with_layout(path):
    import rerun as rr

    bp = rrb.Blueprint(rrb.Horizontal(rrb.TextDocumentView(origin="a", name="Verdict"),
                                      rrb.TextDocumentView(origin="b", name="Notes")))
    with rrd_recording(path, bp, kind="analysis") as rec:
        rec.log("a", rr.TextDocument("x"), static=True)
    return path


def test_the_layout_check_accepts_the_designed_views_and_refuses_others(tmp_path):
    rrd = _rrd_with_layout(tmp_path / "x.rrd")
    designed = blueprint_views(rrd)
    assert sorted(designed.values()) == ["Notes", "Verdict"]
    good = ViewerState("r", ("r",), dict(designed))
    assert layout_problem(good, rrd) is None
    automatic = ViewerState("r", ("r",), {"u1": "/a", "u2": "/b"})
    assert "the blueprint names" in layout_problem(automatic, rrd)
    two = ViewerState("r", ("r", "empty"), dict(designed))
    assert "2 recordings" in layout_problem(two, rrd)
    unselected = ViewerState(None, ("r",), dict(designed))
    assert "selected" in layout_problem(unselected, rrd)
