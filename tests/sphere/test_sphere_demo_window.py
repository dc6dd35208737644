"""`cs451 demo sphere` opens the notes' window (notes §1): 500×500 at (100, 100), titled "Sphere", resizable,
and `q` (through the submission's S8) closes it. Run under Xvfb, as a lecturer's laptop would show it."""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
import textwrap

import pytest

from cs451 import KIT_ROOT

#: Runs the demo in a window; after three frames it records what the window system says about the window,
#: resizes it (S7 must then be called with the new size), and presses q.
SCRIPT = textwrap.dedent("""
    import json, subprocess, sys
    from pathlib import Path
    import glfw
    from cs451.demos import window as W
    from cs451.impl import load_impl
    from cs451.stages import sphere as s1
    from cs451.stages.sphere import demo as _sphere_demo

    seen, sizes = {}, []
    own_keys = W.Window.keys
    def keys(self):
        if self.frames == 3:
            seen["size"], seen["position"] = glfw.get_window_size(self.win), glfw.get_window_pos(self.win)
            seen["resizable"] = bool(glfw.get_window_attrib(self.win, glfw.RESIZABLE))
            seen["xwininfo"] = subprocess.run(["xwininfo", "-name", "Sphere"], capture_output=True, text=True).stdout
            glfw.set_window_size(self.win, 640, 360)
        if self.frames == 8:   # a press of q, through the window's own key callback
            self._on_key(self.win, glfw.KEY_Q, 0, glfw.PRESS, 0)
        return own_keys(self)
    W.Window.keys = keys
    own_reshape = s1._reshape
    def reshape(impl, width, height, camera):
        sizes.append((width, height))
        return own_reshape(impl, width, height, camera)
    s1._reshape = reshape
    module = load_impl(Path(sys.argv[1]), "sphere")
    _sphere_demo.demo(module, Path("."), True, 200)   # q must end it long before 200 frames
    seen["sizes"] = sizes
    print("RESULT " + json.dumps(seen))
""")


@pytest.mark.spawns
def test_the_demo_window_is_the_notes_window_and_q_quits(tmp_path):
    if not shutil.which("xvfb-run") or not shutil.which("xwininfo"):
        pytest.skip("needs xvfb (xvfb-run) and x11-utils (xwininfo)")
    script = tmp_path / "demo_window.py"
    script.write_text(SCRIPT)
    done = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", sys.executable, str(script),
                           str(KIT_ROOT / "reference" / "sphere")], capture_output=True, text=True, timeout=180,
                          cwd=tmp_path)
    lines = [line for line in done.stdout.splitlines() if line.startswith("RESULT ")]
    assert done.returncode == 0 and lines, done.stdout[-2000:] + done.stderr[-2000:]
    seen = json.loads(lines[-1].removeprefix("RESULT "))
    assert tuple(seen["size"]) == (500, 500)
    assert tuple(seen["position"]) == (100, 100)
    assert seen["resizable"]
    assert '"Sphere"' in seen["xwininfo"] and "Width: 500" in seen["xwininfo"]
    sizes = [tuple(s) for s in seen["sizes"]]
    assert sizes[0] == (500, 500) and (640, 360) in sizes, "after the resize, S7 gets the window's new size"
    assert len(sizes) < 50, "q (the submission's S8) should have closed the window"
