"""What the demo window tests share: Xvfb, and a script run in a live window that reports what it saw."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

XVFB = ["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24"]
needs_xvfb = pytest.mark.skipif(shutil.which("xvfb-run") is None, reason="needs Xvfb (xvfb-run) for a window")


def live_window_result(script_text: str, impl: Path, tmp_path: Path) -> dict:
    """Run ``script_text`` under Xvfb with ``impl`` as its argument; the dict its last ``RESULT {json}`` line printed."""
    script = tmp_path / "live.py"
    script.write_text(script_text)
    done = subprocess.run([*XVFB, sys.executable, str(script), str(impl)],
                          capture_output=True, text=True, timeout=300, cwd=tmp_path)
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    assert done.returncode == 0 and lines, done.stdout[-2000:] + done.stderr[-2000:]
    return json.loads(lines[-1].removeprefix("RESULT "))
