"""Lecture slides: the decks in ``slides/`` (Markdown) built into self-contained HTML files.

``build.py`` is the builder (``cs451 slides build``), ``deck.py`` reads a deck, ``listing.py`` pulls the
reference's source lines by function name at build time, and ``figures.py`` renders the figures from the
reference through the stage interfaces. reveal.js and KaTeX are vendored in ``vendor/`` and inlined into
every deck, so a built deck opens offline. Lecturers only: ``cs451 release`` ships none of this.
"""
