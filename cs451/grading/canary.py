"""The canary: a program run exactly as a test runs, before the first test, that must find nothing to use.

Run as ``python -m cs451.grading.canary SPEC`` inside the sandbox, as the sandbox's user, by
:meth:`cs451.grading.sandbox.Sandbox._canary`; ``SPEC`` is JSON (see :func:`main`). It checks that

- every protected path (the kit's reference, specs, history, answer cache; a roster's folders) is unreadable,
  and the staged submission and the results folders are unwritable;
- nothing it can read anywhere holds a copy of the kit's reference or answers (:func:`search`): a folder
  ``reference/<stage>`` with an ``__init__.py``, an ``autograder/<stage>/hidden.py`` or ``truth.py``, an answer
  cache (``.cs451-cache/reference`` or ``truth``), a kit's history (``.git`` beside ``reference/``), an archive
  (zip, wheel, tar) holding one of these, or a source file holding a solution region (``# BEGIN SOLUTION S1``
  … ``# END SOLUTION`` around code).

It prints one JSON line; the sandbox refuses to grade on any finding, and when the search did not finish.
Under bubblewrap the search covers the few folders the sandbox binds; in the uid-only fallback it covers
the whole host, which that fallback cannot hide: a world-readable copy of the kit anywhere stops grading.
"""
from __future__ import annotations

import json
import os
import re
import sys
import tarfile
import time
import zipfile
from pathlib import PurePosixPath

#: Never walked: the kernel's views and devices.
SKIPPED = ("/proc", "/sys", "/dev")
#: Walked for names and archives, never read as text: the system's own files and installed packages.
NOT_READ = ("/usr", "/lib", "/lib32", "/lib64", "/libx32", "/bin", "/sbin", "/etc", "/boot", "/snap", "/var/lib",
            "/var/cache", "/var/log")
ZIPS = (".zip", ".whl", ".egg", ".pyz")
TARS = (".tar", ".tar.gz", ".tgz", ".tar.xz", ".tar.bz2")
TEXT = (".py", ".pyw", ".ipynb", ".txt", ".md", ".rst", ".json")
TEXT_BYTES = 1 << 20          # larger text files are not read
TAR_BYTES = 64 << 20          # larger compressed tars are not opened (their members are read to list them)
REGION = re.compile(rb"^[ \t]*# BEGIN SOLUTION [A-Z]+\d+[a-z]?\b[^\n]*\n(?P<body>(?:(?![ \t]*# END SOLUTION)[^\n]*\n)*?)"
                    rb"[ \t]*# END SOLUTION", re.M)


def secret_in_parts(parts: tuple[str, ...], stages: set[str]) -> str | None:
    """Why a path (as its parts) is a copy of the kit's reference, hidden tests or answers, or of the engine's
    instructors-only parts (a stage's benchmarks, deck figures or speed layer, which would answer tasks), or None."""
    for i in range(len(parts) - 1):
        here, below = parts[i], parts[i + 1]
        if here == "stages" and below in stages and i > 0 and parts[i - 1] == "cs451" and i + 2 < len(parts) \
                and _instructors(parts[i + 2]):
            return f"stage {below}'s {parts[i + 2]} (instructors only: benchmarks, figures and speed layers answer tasks)"
        if here == "reference" and below in stages and i + 2 < len(parts):
            return f"the reference of stage {below}"
        if here == "autograder" and below in stages and i + 2 < len(parts) and parts[i + 2] in ("hidden.py", "truth.py"):
            return f"stage {below}'s {parts[i + 2]}"
        if here == ".cs451-cache" and below in ("reference", "truth"):
            return "a grader's answer cache"
    return None


def _instructors(name: str) -> bool:
    """Whether a name in a stage's package is one of the engine's instructors-only parts (:func:`cs451.instructor_only`)."""
    from .. import INSTRUCTOR_FILES, INSTRUCTOR_PREFIXES, SPEED_LAYER
    return name in INSTRUCTOR_FILES or name == SPEED_LAYER or (name.startswith(INSTRUCTOR_PREFIXES)
                                                               and name.endswith(".py"))


def solution_region(data: bytes) -> bool:
    """Whether ``data`` holds a solution region around code (not an example whose body is ``...``)."""
    if b"# BEGIN SOLUTION" not in data:
        return False
    for match in REGION.finditer(data):
        body = [line.strip() for line in match.group("body").splitlines() if line.strip()]
        if [line for line in body if line.strip(b".") and line not in (b"...solution...", b"pass")]:
            return True
    return False


def _archive_secret(path: str, stages: set[str]) -> str | None:
    names: list[str] = []
    try:
        if path.endswith(ZIPS):
            with zipfile.ZipFile(path) as z:        # reads the central directory only
                names = z.namelist()
        elif path.endswith(TARS) and os.path.getsize(path) <= TAR_BYTES:
            with tarfile.open(path) as t:
                names = t.getnames()
    except (OSError, zipfile.BadZipFile, tarfile.TarError, EOFError, ValueError):
        return None
    for name in names:
        why = secret_in_parts(PurePosixPath(name).parts, stages)
        if why:
            return f"{why} inside the archive (as {name})"
    return None


def _text_secret(path: str) -> str | None:
    try:
        with open(path, "rb", opener=lambda p, f: os.open(p, f | os.O_NONBLOCK | getattr(os, "O_NOFOLLOW", 0))) as f:
            if not os.path.isfile(path) or os.fstat(f.fileno()).st_size > TEXT_BYTES:
                return None
            data = f.read(TEXT_BYTES)
    except OSError:
        return None
    return "a solution region (# BEGIN SOLUTION … # END SOLUTION)" if solution_region(data) else None


def _under(path: str, tops: tuple[str, ...] | list[str]) -> bool:
    return any(path == t or path.startswith(t.rstrip("/") + "/") for t in tops)


def search(top: str, stages: set[str], exempt: list[str], deadline: float, student_copy: bool = False,
           limit: int = 40) -> tuple[list[str], bool, int]:
    """Everything readable below ``top`` (no link followed) that holds the kit's reference or answers.

    Returns ``(findings as "path: why", whether the search finished before deadline, entries looked at)``.
    ``exempt``: folders the grader gives the sandbox on purpose (the staged upload, the job folder, an earlier
    stage's reference the engine draws with); in a ``student_copy`` a ``.git`` is the student's own.
    """
    found: list[str] = []
    seen = 0
    for folder, dirs, files in os.walk(top):
        if time.monotonic() > deadline:
            return found, False, seen
        if _under(folder, SKIPPED) or _under(folder, exempt):
            dirs[:] = []
            continue
        seen += len(dirs) + len(files)
        parts = PurePosixPath(folder).parts
        why = secret_in_parts(parts + ("",), stages)   # the folder itself lies in a reference/<stage>/ or a cache
        if why:
            found.append(f"{folder}: {why}")
            dirs[:] = []
            if len(found) >= limit:
                return found, True, seen
            continue
        for name in dirs + files:
            path = os.path.join(folder, name)
            if name in dirs:
                why = "a kit's history (.git beside reference/)" if (name == ".git" and "reference" in dirs
                                                                     and not student_copy
                                                                     and os.access(path, os.R_OK | os.X_OK)) else None
            elif name.endswith(ZIPS + TARS):
                why = _archive_secret(path, stages)
            else:
                why = secret_in_parts(parts + (name,), stages)
                if not why and name.endswith(TEXT) and not _under(folder, NOT_READ) and "site-packages" not in parts \
                        and "dist-packages" not in parts:
                    why = _text_secret(path)
            if why and not _under(path, exempt):
                found.append(f"{path}: {why}")
                if len(found) >= limit:
                    return found, True, seen
    return found, True, seen


def _readable(path: str) -> bool:
    try:
        os.listdir(path) if os.path.isdir(path) else open(path, "rb").close()
        return True
    except OSError:
        return False


def _writable(folder: str) -> bool:
    try:
        open(os.path.join(folder, "cs451-canary"), "x").close()
        return True
    except OSError:
        return False


def main(argv: list[str]) -> int:
    """``SPEC``: ``protected`` (paths), ``unwritable`` (folders), ``exempt`` (folders), ``stages`` (names),
    ``student_copy`` (bool), ``seconds`` (the search's budget)."""
    spec = json.loads(argv[0])
    start = time.monotonic()
    seen = [p for p in spec["protected"] if _readable(p)]
    wrote = [p for p in spec["unwritable"] if _writable(p)]
    import cs451  # noqa: F401  (the engine imports as a test's worker would)
    found, complete, entries = search("/", set(spec["stages"]), spec["exempt"], start + spec["seconds"],
                                      spec.get("student_copy", False))
    print(json.dumps({"seen": seen, "wrote": wrote, "uid": os.getuid(), "found": found, "complete": complete,
                      "entries": entries}))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
