"""Text from data made safe to show: control characters and escape sequences made visible.

Names in recordings, scenarios, campaigns and run directories come from someone else. Printed as
they are, a carriage return or an ANSI sequence (``\\r\\x1b[2K``) rewrites what the terminal
shows: a module named ``prediction\\r\\x1b[2KInitial deviating module: planning`` would show the
user "planning". :func:`printable` turns every such character into a visible escape (``\\r``,
``\\x1b``), so the name reads as what it is; rich markup is escaped by the console's own helper
(:func:`rocas.cli.console.safe`), HTML by :func:`html.escape` where a page embeds names.
"""

from __future__ import annotations

import re

_NAMED = {"\n": "\\n", "\r": "\\r", "\t": "\\t"}
#: characters a terminal acts on instead of showing: C0 and C1 controls, DEL, and the format
#: characters that reorder or hide text (bidirectional overrides, zero-width joiners)
_UNSHOWN = re.compile(r"[\x00-\x1f\x7f-\x9f\u200b-\u200f\u202a-\u202e\u2066-\u2069\ufeff]")


def _visible(m: re.Match[str]) -> str:
    c = m.group()
    if c in _NAMED:
        return _NAMED[c]
    code = ord(c)
    return f"\\x{code:02x}" if code < 0x100 else f"\\u{code:04x}"


def printable(text: object) -> str:
    """``str(text)`` with every control, escape and invisible formatting character shown as
    its Python escape (``\\x1b``, ``\\r``, ``\\u202e``); other text is unchanged."""
    s = str(text)
    if s.isprintable():
        return s
    return _UNSHOWN.sub(_visible, s)



def markdown_text(text: object) -> str:
    """``text`` (a name from data) for a Markdown table cell or line: :func:`printable`, HTML
    escaped (a renderer shows ``<img onerror=...>`` as text, never as markup) and with the
    characters Markdown acts on in a cell (``|``, backticks, ``*``, ``[``, ``\\``) escaped
    (``_`` inside a word, as in every catalog name, is left: Markdown does not act on it)."""
    import html

    s = html.escape(printable(text), quote=False)  # quotes act only inside a tag
    return re.sub(r"([\\\\`*\[\]|])", r"\\\1", s)
