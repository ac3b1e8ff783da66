"""The output boundary: names from data made printable, rich-safe and Markdown-safe."""

import io

from rich.console import Console

from rocas._text import markdown_text, printable
from rocas.cli.console import prose, safe


def test_printable_shows_what_a_terminal_would_act_on():
    assert printable("planning") == "planning"
    assert printable("a\r\x1b[2Kb") == "a\\r\\x1b[2Kb"
    assert printable("x\ny\tz\x00\x7f\x9b") == "x\\ny\\tz\\x00\\x7f\\x9b"
    assert printable("evil\u202eexe.txt\u200b") == "evil\\u202eexe.txt\\u200b"
    assert printable("Übergang → Kreuzung") == "Übergang → Kreuzung"  # text is text
    assert printable(3) == "3"


def test_safe_names_print_as_they_read_on_a_rich_console():
    out = io.StringIO()
    con = Console(file=out, highlight=False, width=200)
    names = ["[/", "[bold]x[/bold]", "fore[/]caster[bold]",
             "tracker\r\x1b[2KInitial deviating module: planning"]
    for n in names:
        con.print(f"[bold]name[/bold]: {safe(n)}")
    prose(con, "prose: " + names[0] + " and " + names[3])
    lines = out.getvalue().splitlines()
    assert lines[:4] == [f"name: {printable(n)}" for n in names]
    assert lines[4] == f"prose: [/ and {printable(names[3])}"
    assert "\x1b" not in out.getvalue()


def test_markdown_text_escapes_html_and_table_markup():
    assert markdown_text("a07_rear_ended_at_red") == "a07_rear_ended_at_red"
    assert markdown_text("Algorithm 1's walk") == "Algorithm 1's walk"
    assert markdown_text("<script>x</script>") == "&lt;script&gt;x&lt;/script&gt;"
    assert markdown_text("a|b `c` *d* [e](f)") == "a\\|b \\`c\\` \\*d\\* \\[e\\](f)"
    assert markdown_text("x\r\x1b") == "x\\\\r\\\\x1b"
