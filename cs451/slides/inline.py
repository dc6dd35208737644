"""A deck's inline markdown as HTML: emphasis, code, links and math inside one line of a slide, escaped, and
the raw HTML a deck may hold checked against the few tags it may use. Errors name the deck's file and line.
"""
from __future__ import annotations

import re
from html import escape

from ..errors import KitError

#: A markdown link, [text](target).
LINK = re.compile(r"\[([^\]]+)\]\(([^)\s]+)\)")


def inline_html(text: str, where: str) -> str:
    """One line or paragraph of text as HTML: code spans and math first (nothing inside them is markup)."""
    out, i, plain = [], 0, []

    def flush() -> None:
        if plain:
            out.append(checked_markup(escape("".join(plain), quote=False), where))
            plain.clear()
    while i < len(text):
        ch = text[i]
        if ch == "\\" and text[i + 1:i + 2] == "$":
            plain.append("$")
            i += 2
        elif ch == "`":
            end = text.find("`", i + 1)
            if end < 0:
                raise KitError(f"{where}: a ` opens code that no ` closes")
            flush()
            out.append(f"<code>{escape(text[i + 1:end])}</code>")
            i = end + 1
        elif ch == "$":
            end = i + 1
            while True:
                end = text.find("$", end)
                if end < 0 or text[end - 1] != "\\":
                    break
                end += 1
            tex = text[i + 1:end] if end > 0 else ""
            if end < 0 or not tex.strip() or tex != tex.strip():
                raise KitError(f"{where}: a $ opens math that no $ closes (write \\$ for a dollar sign)")
            flush()
            out.append(f'<span class="math inline" data-source="{escape(where)}">{escape(tex)}</span>')
            i = end + 1
        else:
            plain.append(ch)
            i += 1
    flush()
    return "".join(out)


def checked_markup(html: str, where: str) -> str:
    if "![" in html:
        raise KitError(f"{where}: an image goes on a line of its own: ![caption](figure:NAME)")

    def link(m: re.Match) -> str:
        target = m.group(2)
        if not target.startswith(("https://", "http://", "#")):
            raise KitError(f"{where}: link {target!r}: a deck links to web pages (https://…) or slides (#/3) only")
        return f'<a href="{target}">{m.group(1)}</a>'
    html = LINK.sub(link, html)
    html = re.sub(r"\*\*(\S(?:.*?\S)?)\*\*", r"<strong>\1</strong>", html)
    html = re.sub(r"(?<![\w*])\*(\S(?:.*?\S)?)\*(?![\w*])", r"<em>\1</em>", html)
    return html

