"""Before a submission's first test: choosing the isolation that works here, and the canary that must find nothing
to use under it (:mod:`.canary`). Grading stops, saying why, when no isolation passes.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

import json
import os
import shutil
import stat
import sys
from pathlib import Path

try:  # not on Windows: there the student copy runs without limits (nothing to protect)
    import resource
except ImportError:  # pragma: no cover
    resource = None  # type: ignore[assignment]


from .processes import IsolationError
from .scratch import (is_root, private_folder_above)

from .workers import Limits

if TYPE_CHECKING:
    from .sandbox import Sandbox

CANARY_SECONDS = 90.0          # the canary's whole run
CANARY_SEARCH_SECONDS = 60.0   # its search of everything the sandbox user can read


# -- choosing the isolation --
def choose_mode(box: Sandbox) -> str:
    """The isolation to grade under: the first that works of what ``CS451_SANDBOX`` (or the sandbox) asks for, its
    canary passed; else refuse, saying what was tried and how to fix it."""
    wanted = os.environ.get("CS451_SANDBOX", box.mode)
    if wanted not in ("auto", "bubblewrap", "uid", "none"):
        raise IsolationError(f"CS451_SANDBOX={wanted!r}: expected auto, bubblewrap, uid or none")
    reasons = []
    candidates = ["bubblewrap", "uid", "none"] if wanted == "auto" else [wanted]
    for mode in candidates:
        problem = usable(box, mode)
        if problem is None:
            return mode
        reasons.append(f"{mode}: {problem}")
    tried = " (" + "; ".join(reasons) + ")"
    blocked = unreachable(box) if is_root() else None
    if blocked is not None:
        what, needed, private = blocked
        raise IsolationError(
            f"the submission cannot be isolated here, so it is not run: its tests run as a throwaway user, never "
            f"as root, and that user cannot reach {what} {needed}: {private} lets no other user pass through "
            f"(mode {stat.S_IMODE(os.stat(private).st_mode):04o}). Let others pass through it (chmod o+x "
            f"{private}: they may then open what is inside by name, not list it), move the repository to a "
            f"folder they may pass through and run its ./setup.sh again there, or grade as an ordinary user"
            + tried)
    fixes = [f for f, needed in (("install bubblewrap (apt-get install bubblewrap)", not shutil.which("bwrap")),
                                 ("grade as root", not is_root())) if needed]
    raise IsolationError("the submission cannot be isolated here, so it is not run" + tried +
                         (". " + " or ".join(fixes)[:1].upper() + " or ".join(fixes)[1:] + "." if fixes else "."))


def needed_outside(box: Sandbox) -> list[tuple[str, str]]:
    """What the sandbox's user must reach by path before any namespace exists: (what it is, path)."""
    needed = [("the Python interpreter", sys.executable)]
    needed += [("the Python environment", prefix) for prefix in
               sorted({sys.prefix, sys.base_prefix, sys.exec_prefix, sys.base_exec_prefix})]
    needed += [("the library folder", lib) for lib in os.environ.get("LD_LIBRARY_PATH", "").split(":")
               if lib and os.path.isdir(lib)]
    if box.run_dir is not None:
        needed.append(("the grading folder", str(box.run_dir)))
    return needed


def unreachable(box: Sandbox) -> tuple[str, str, Path] | None:
    """The first needed path behind a folder that users other than its owner may not pass through (mode bits
    only: the usual cause of a refusal as root, e.g. a repository in /root or under a private folder)."""
    for what, path in needed_outside(box):
        private = private_folder_above(Path(path))
        if private is not None:
            return what, path, private
    return None


def usable(box: Sandbox, mode: str) -> str | None:
    """None where ``mode`` can grade here, else why not, in words for the refusal: ``none`` only in a student copy
    and never as root; the others once their canary passes, run with the sandbox set to that mode."""
    if mode == "none":
        if is_root():
            return "never as root"
        if not box.student_copy:
            return "this kit holds the reference or hidden tests, which a submission must not read"
        return None
    if mode == "bubblewrap" and not shutil.which("bwrap"):
        return "bwrap is not installed"
    if mode == "uid" and not is_root():
        return "needs root"
    box.mode = mode
    box.uid_for_tests = is_root()
    return run_canary(box)


def run_canary(box: Sandbox) -> str | None:
    """Run :mod:`.canary` exactly as a test would: it must see no protected path and no copy of the kit's
    reference or answers anywhere it can read, and change nothing it is given."""
    from ..stages import stage_names
    job = box._new_job()
    given = [f"{box.visible_engine}/{below}" for _, below in box.engine_sources if below != "cs451"]
    spec = {"protected": [str(p) for p in box.protected if os.path.lexists(p)],
            "unwritable": [box.visible_upload] + [str(p) for p in box.unwritable if os.path.isdir(p)],
            "exempt": [box.visible_upload, box.visible_job(job), str(Path(box.upload).absolute()), *given],
            "stages": stage_names(),
            "student_copy": box.student_copy, "seconds": CANARY_SEARCH_SECONDS}
    try:
        done = box.run(["-m", "cs451.grading.canary", json.dumps(spec)], job, Limits(wall_seconds=CANARY_SECONDS))
    except OSError as err:
        return f"could not start ({err})"
    finally:
        box._finish_job(job)
    try:
        answer = json.loads(done.output.strip().splitlines()[-1])
    except (ValueError, IndexError):
        return f"the canary did not run ({done.output.strip()[-300:] or f'exit {done.returncode}'})"
    if answer["seen"]:
        return (f"the sandbox user can read {', '.join(answer['seen'][:3])}; make those private "
                f"(chmod go-rwx) or install bubblewrap")
    if answer["wrote"]:
        for folder in answer["wrote"][1:]:
            (Path(folder) / "cs451-canary").unlink(missing_ok=True)
        return f"the sandbox user can write in {answer['wrote'][0]}"
    if answer["found"]:
        return (f"the sandbox user can read a copy of the kit's reference or answers: "
                f"{'; '.join(answer['found'][:3])}{' and more' if len(answer['found']) > 3 else ''}; remove it or "
                f"make it private (mode 0700){'' if box.mode == 'bubblewrap' else ', or install bubblewrap'}")
    if not answer["complete"]:
        return (f"the canary could not search everything the sandbox user can read in {CANARY_SEARCH_SECONDS:g} s "
                f"({answer['entries']} entries); install bubblewrap, which shows it far less")
    if is_root() and answer["uid"] == 0:
        return "the worker would run as root"
    return None

