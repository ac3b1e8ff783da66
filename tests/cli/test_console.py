"""The consoles commands print through (rocas.cli.console)."""

from __future__ import annotations

import io

from rich.panel import Panel

from rocas.cli.console import Env, prose


def test_piped_prose_is_not_broken_across_lines_and_panels_still_wrap():
    out = io.StringIO()
    sentence = " ".join(["word"] * 60)  # 299 characters, more than the 160 columns piped output gets
    console = Env(stdout=out).out()
    prose(console, sentence)
    assert out.getvalue() == sentence + "\n"
    console.print(Panel(sentence))
    assert out.getvalue().count("word") == 120  # wrapped inside the panel, not cut off
