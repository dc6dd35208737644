"""The student side of grading: import a submission, run one probe, write the arrays it returns.

Run as ``python -m cs451.grading.worker JOB_DIR`` by :mod:`cs451.grading.runner`,
never imported by the grader. ``JOB_DIR/request.json`` names the stage, the
implementation folder, the probe and its parameters; trusted inputs arrive in
``JOB_DIR/inputs.npz``. The answer goes to ``JOB_DIR/output.npz`` and
``JOB_DIR/status.json``; the grader reads them as untrusted data.
"""
from __future__ import annotations

import errno
import json
import sys
import traceback
from pathlib import Path

import numpy as np


def _write_status(job: Path, ok: bool, error: str = "") -> None:
    (job / "status.json").write_text(json.dumps({"ok": ok, "error": error[:2000]}))


def _student_frame(tb: traceback.StackSummary, impl_dir: str) -> str:
    """The deepest line of the traceback inside the submission, so the message points at the student's code."""
    for frame in reversed(tb):
        if frame.filename.startswith(impl_dir):
            return f" (at {Path(frame.filename).name}:{frame.lineno})"
    return ""


def run(job: Path) -> int:
    """Answer the job's request: load the submission, run its probe (or the interface check), write output.npz and
    status.json; returns 0 once status.json is written, since a failure goes there and not in the exit code."""
    from ..errors import KitError
    from ..impl import load_impl
    from ..stages import get_stage
    from ..stages.base import check_interface

    request = json.loads((job / "request.json").read_text())
    stage = get_stage(request["stage"])
    impl_dir = request["impl"]
    try:
        impl = load_impl(Path(impl_dir), stage.name)
        if request["probe"] == "__interface__":
            problems = check_interface(stage, impl)
            np.savez(job / "output.npz", problems=np.array(problems, dtype=str))
            _write_status(job, True)
            return 0
        inputs = {}
        if (job / "inputs.npz").exists():
            with np.load(job / "inputs.npz", allow_pickle=False) as data:
                inputs = {k: data[k] for k in data.files}
        outputs = stage.probes[request["probe"]](impl, **request["params"], **inputs)
        np.savez(job / "output.npz", **outputs)
        _write_status(job, True)
    except KitError as err:
        _write_status(job, False, str(err))
    except OSError as err:
        if err.errno == errno.EFBIG:  # RLIMIT_FSIZE: Python ignores SIGXFSZ, so the write fails instead
            _write_status(job, False, "the submission wrote more output than allowed (File too large)")
        else:
            where = _student_frame(traceback.extract_tb(err.__traceback__), impl_dir)
            _write_status(job, False, f"{type(err).__name__}: {err}{where}")
    except MemoryError:
        _write_status(job, False, "MemoryError: the submission ran out of memory")
    except RecursionError:
        _write_status(job, False, "RecursionError: maximum recursion depth exceeded")
    except Exception as err:  # the submission's own bug: report it, one line, pointing at its code
        where = _student_frame(traceback.extract_tb(err.__traceback__), impl_dir)
        _write_status(job, False, f"{type(err).__name__}: {err}{where}")
    return 0


if __name__ == "__main__":
    sys.exit(run(Path(sys.argv[1])))
