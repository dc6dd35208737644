"""``cs451 slides pdf``: a built deck printed to a real PDF, one slide a page, by headless Chromium.

Printing from a browser's command line (``chromium --print-to-pdf``) prints the page before reveal.js has laid
the slides out for print, which gives blank pages. Here the page is opened with ``?print-pdf``, the kit's deck
script reports when reveal.js's print layout is done (``cs451Deck.printReady``), and only then is it printed,
through the DevTools protocol, at the page size the layout asks for.
"""
from __future__ import annotations

import base64
import os
import re
import tempfile
from pathlib import Path

from ..errors import KitError
from .chromium import Chromium

#: Waits until reveal.js has laid the deck out for print, and every image in it has loaded.
PRINT_READY = """new Promise((done, fail) => { const t0 = Date.now(); (function wait() {
  const images = [...document.images].every(i => i.complete && i.naturalWidth > 0);
  if (window.cs451Deck && cs451Deck.printReady && images) done(true);
  else if (Date.now() - t0 > 60000) fail(new Error('the print layout never finished'));
  else setTimeout(wait, 50); })(); })"""


def print_deck(browser: Chromium, html: Path, pdf: Path) -> int:
    """Print one built deck to ``pdf``; returns the number of pages written."""
    page = browser.page()
    try:
        page.open(html.resolve().as_uri() + "?print-pdf")
        page.eval(PRINT_READY)
        data = base64.b64decode(page.call("Page.printToPDF", {"preferCSSPageSize": True, "printBackground": True},
                                          timeout=300)["data"])
    finally:
        page.call("Page.close")
    if not data.startswith(b"%PDF"):
        raise KitError(f"{html}: Chromium gave no PDF")
    pdf.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{pdf.stem}-", suffix=".pdf", dir=pdf.parent)
    try:
        with os.fdopen(fd, "wb") as out:
            out.write(data)
        os.replace(tmp, pdf)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise
    return page_count(data)


def page_count(data: bytes) -> int:
    """Pages of a PDF as Chromium writes it (one ``/Type /Page`` object each)."""
    return len(re.findall(rb"/Type\s*/Page[^s]", data))
