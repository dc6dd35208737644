"""What ``cs451 slides build | check | pdf | record`` do, behind the command line's parsing (``cs451/cli.py``)."""
from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

from ..errors import KitError
from ..progress import Progress


def cmd_build(a: argparse.Namespace) -> int:
    from .build import build_summary, timed_build
    built, seconds = timed_build(output=a.output, deck=a.deck, cache=a.cache, quick=a.quick)
    for b in built:
        print(f"wrote {b.path} ({b.slides} slides, {b.figures} figures, {b.bytes / 1e6:.1f} MB)")
    print(build_summary(built, seconds) + "; each file opens offline (open it in a browser; `cs451 slides pdf` prints it)")
    return 0


def cmd_check(a: argparse.Namespace) -> int:
    """Build the decks into a scratch folder and measure every slide in headless Chromium at 1920 × 1080 and
    1280 × 720; exit 1 if any floor is broken, printing each breach."""
    from .build import build_slides
    from .chromium import Chromium, chromium_or_refuse
    from .readability import as_json, measure_deck, summary
    chromium_or_refuse()
    with tempfile.TemporaryDirectory(prefix="cs451-slides-") as scratch:
        built = build_slides(output=scratch, deck=a.deck, cache=a.cache, quick=a.quick)
        failed = 0
        reports = []
        bar = Progress("slides: measuring", len(built), unit="deck")
        try:
            with Chromium() as browser:
                for b in built:
                    results = measure_deck(browser, b.path)
                    bar.advance(1, note=b.deck)
                    reports.append(as_json(b.deck, results))
                    for m in results:
                        for p in m.problems:
                            print(p)
                        failed += len(m.problems)
                    print(summary(b.deck, results))
        finally:
            bar.close()
    if a.json:
        Path(a.json).write_text("[" + ",".join(r.strip()[1:-1] for r in reports) + "]\n")
    if failed:
        print(f"{failed} readability problems (floors: text 24 px, code 20 px, figure text 16 px, figures at 2 "
              "pixels per slide pixel, nothing under the controls)", file=sys.stderr)
        return 1
    return 0


def cmd_pdf(a: argparse.Namespace) -> int:
    """Build the decks and print each to a PDF: ``-o`` names the file for one deck, or a folder."""
    from .build import build_slides
    from .chromium import Chromium, chromium_or_refuse
    from .pdf import print_deck
    chromium_or_refuse()
    out = Path(a.output)
    with tempfile.TemporaryDirectory(prefix="cs451-slides-") as scratch:
        built = build_slides(output=scratch, deck=a.deck, cache=a.cache, quick=a.quick)
        one_file = out.suffix.lower() == ".pdf"
        if one_file and len(built) != 1:
            raise KitError(f"-o {out}: names one PDF, but {len(built)} decks are printed: give a folder, or a deck")
        if out.exists() and not one_file and not out.is_dir():
            raise KitError(f"-o {out}: is a file, not a folder")
        with Chromium() as browser:
            for b in built:
                target = out if one_file else out / f"{b.deck}.pdf"
                try:
                    pages = print_deck(browser, b.path, target)
                except OSError as err:
                    raise KitError(f"-o {target}: cannot write there ({err.strerror or err})") from None
                print(f"wrote {target} ({pages} pages, one per slide)")
    return 0


def cmd_record(a: argparse.Namespace) -> int:
    """Measure the benchmark figures' records, one after another, and write them to slides/records/."""
    from .records import record
    record(a.names or None, quick=a.quick, repeats=a.repeats, folder=Path(a.output) if a.output else None)
    return 0
