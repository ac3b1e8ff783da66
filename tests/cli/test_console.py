"""The consoles commands print through (rocas.cli.console)."""

from __future__ import annotations

import io

from rocas.cli.console import Env


def test_piped_prose_is_not_broken_across_lines():
    out = io.StringIO()
    sentence = " ".join(["word"] * 60)  # 299 characters, more than the 160 columns tables get
    Env(stdout=out).out().print(sentence)
    assert out.getvalue() == sentence + "\n"
