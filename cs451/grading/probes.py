"""One probe run in one fresh worker, and what its exit and files mean: shared by the grader (a submission, in the
sandbox) and the answer cache (the kit's own reference, trusted, in a plain subprocess).
"""
from __future__ import annotations

import json
import sys
import tempfile
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from .. import ENGINE_DIR
from . import sandbox
from .spec import Outputs
from .untrusted import UntrustedError, read_arrays, read_status, signal_name


@dataclass
class ProbeResult:
    ok: bool
    outputs: Outputs
    error: str
    output: str
    seconds: float


def interpret(done: sandbox.Completed, job: Path, timeout: float, seconds: float,
               memory: int = sandbox.SUBMISSION_MEMORY) -> ProbeResult:
    """What a finished worker means, from its exit and the files it left (read as hostile data)."""
    if done.out_of_memory:
        return ProbeResult(False, {}, f"the submission ran out of memory (everything it starts may use "
                                      f"{memory >> 20} MiB together)", done.output, seconds)
    if done.timed_out:
        return ProbeResult(False, {}, f"took longer than the {timeout:g} s limit (an infinite loop?)", done.output, seconds)
    if done.disk_full:
        return ProbeResult(False, {}, f"the submission wrote more to disk than a test may keep ({sandbox.JOB_DISK >> 20} "
                                      f"MiB in its folder, {sandbox.TMP_DISK >> 20} MiB in /tmp)", done.output, seconds)
    try:
        ok, error = read_status(job / "status.json")
        outputs = read_arrays(job / "output.npz") if ok else {}
    except UntrustedError as err:
        if "status.json is missing" in str(err):
            error = "the submission stopped before finishing this test (it crashed, exited or was killed)"
        else:
            error = f"the answer could not be read: {err}"
        ok, outputs = False, {}
    sig = signal_name(done.returncode)
    if not ok and sig:
        reason = {"SIGXCPU": "it used more CPU time than allowed", "SIGXFSZ": "it wrote more output than allowed",
                  "SIGKILL": "it was killed (out of memory?)", "SIGSEGV": "it crashed (segmentation fault)"}
        error = f"the submission stopped: {reason.get(sig, sig)}"
    elif not ok and "MemoryError" in error:
        error += f" (the limit is {sandbox.MEMORY_LIMIT >> 30} GiB)"
    return ProbeResult(ok, outputs, error or "failed without a message", done.output, seconds)


def write_request(job: Path, stage: str, impl: str, probe: str, params: dict[str, Any], inputs: Outputs | None) -> None:
    """Put a probe's request (request.json) and its trusted inputs (inputs.npz) in the job folder the worker reads."""
    (job / "request.json").write_text(json.dumps({"stage": stage, "impl": impl, "probe": probe, "params": params}))
    if inputs:
        np.savez(job / "inputs.npz", **inputs)


def run_trusted_probe(stage: str, impl_dir: Path, probe: str, params: dict[str, Any],
                      inputs: Outputs | None = None, timeout: float = 300.0) -> ProbeResult:
    """Run one probe on the kit's own reference in a plain subprocess (trusted: no sandbox)."""
    start = time.perf_counter()
    with tempfile.TemporaryDirectory(prefix="cs451-trusted-") as tmp:
        job = Path(tmp) / "job"
        job.mkdir()
        write_request(job, stage, str(impl_dir), probe, params, inputs)
        done = sandbox.run_trusted([sys.executable, "-m", "cs451.grading.worker", str(job)], job,
                                   sandbox.Limits(wall_seconds=timeout), engine=ENGINE_DIR.parent)
        return interpret(done, job, timeout, time.perf_counter() - start)
