"""One-line errors for bad input: the CLI prints them without a traceback."""
from __future__ import annotations


class KitError(Exception):
    """An error a user can fix; the CLI prints ``str(err)`` and exits with status 2."""


class InputError(KitError):
    """Bad data in a file: names the file and the JSON path of the offending field."""

    def __init__(self, file: str, path: str, message: str):
        self.file, self.path, self.message = file, path, message
        where = f"{file}: {path}" if path else file
        super().__init__(f"{where}: {message}")


class SubmissionError(KitError):
    """The submission itself cannot be graded (no package in it, too large, not a folder): the student can fix it."""
