"""Packaging a stage for the platforms instructors use: a Gradescope autograder zip and a student repository.

Both are built from this checkout, so they never drift from the kit:
- :mod:`.gradescope` builds the zip Gradescope runs for every submission (with the reference and the hidden tests);
- :mod:`.release` builds the starter repository students clone (GitHub Classroom's template): the starter,
  the public tests with the reference's answers to them, and a workflow that runs them on push.
"""
