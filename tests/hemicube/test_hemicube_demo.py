"""`cs451 demo hemicube` (stage 3's demo): a frame per patch of a sweep, a painted row that is the engine's row (the
sum the caption gives, the colours the stage's ramp gives it), item buffers that sum to the engine's hemicube row,
clicks and keys that pick patches and settings, and the window under Xvfb showing what the headless frame shows."""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
import textwrap

import numpy as np
import pytest
from PIL import Image

from cs451 import KIT_ROOT
from cs451.formfactors import HemicubeFormFactors
from cs451.impl import load_impl
from cs451.imageio import load_png
from cs451.patches import scene_polygons
from cs451.scene import load_scene
from cs451.stages import hemicube as H
from cs451.stages.hemicube.demo import HemicubeDemo

from demo_windows import XVFB, live_window_result, needs_xvfb

REF = load_impl(KIT_ROOT / "reference" / "hemicube", "hemicube")
QUADS = scene_polygons(load_scene("cornell-box"))[0]


def cs451(*args: str, display: bool = False, timeout: int = 300) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if display or k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run(([*XVFB] if display else []) + [sys.executable, "-m", "cs451", *args], cwd=KIT_ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The headless sweep on a copy of the reference in a folder of its own, as a submission."""
    root = tmp_path_factory.mktemp("hemicube-demo")
    shutil.copytree(KIT_ROOT / "reference" / "hemicube", root / "sub" / "hemicube",
                    ignore=shutil.ignore_patterns("__pycache__"))
    done = cs451("demo", "hemicube", "--impl", str(root / "sub"), "-o", str(root / "frames"))
    assert done.returncode == 0, done.stderr[-2000:]
    return root


@pytest.fixture(scope="module")
def demo():
    d = HemicubeDemo(REF)
    d.start(None)
    return d


def shown(d: HemicubeDemo, patch: int) -> HemicubeDemo:
    d.patch = patch
    while d.busy():
        d.step(0.05)
    return d


@pytest.mark.spawns
def test01_the_sweep_writes_a_frame_per_patch(run):
    frames = sorted((run / "frames").glob("hemicube-*.png"))
    assert len(frames) == len(QUADS) == 16
    with Image.open(run / "frames" / "hemicube.gif") as gif:
        assert gif.n_frames == 16
    first, second = load_png(frames[0]), load_png(frames[1])
    assert first.shape == second.shape and not np.array_equal(first, second)


@pytest.mark.parametrize("patch", [0, 2, 8, 15])
def test02_the_painted_row_is_the_engines_and_its_sum_is_in_the_caption(demo, patch):
    d = shown(demo, patch)
    engine = HemicubeFormFactors(QUADS, H.calls(REF), resolution=128, rotate=False)       # as `cs451 render` builds it
    assert d.painted_row().sum() == pytest.approx(engine.row(patch).sum(), abs=1e-12)
    bare = HemicubeFormFactors(QUADS, H.calls(REF), resolution=128, rotate=False, proximity="none")
    assert np.allclose(d.shown.hemicube_row, bare.row(patch), rtol=0, atol=1e-15), \
        "H5 over the item buffers shown is the engine's hemicube row"
    assert f"row sum {engine.row(patch).sum():.4f}" in d._caption()[0]


def test03_the_scene_is_painted_with_the_stages_ramp(demo):
    d = shown(demo, 0)
    frame = d.frame().astype(np.float64) / 255
    left, top, w, h = d.layout["scene"]
    red = frame[top:top + h, left:left + w, 0]
    linear = np.where(red <= 0.04045, red / 12.92, ((red + 0.055) / 1.055) ** 2.4)     # the frame is sRGB-encoded
    row = d.painted_row()
    checked = 0
    for j in range(d.n):
        pixels = d.ids == j
        if j == d.patch or pixels.sum() < 20:
            continue
        assert np.median(linear[pixels]) == pytest.approx(row[j] / row.max(), abs=0.01), j
        checked += 1
    assert checked >= 8
    shooter = frame[top:top + h, left:left + w][d.ids == d.patch]
    assert len(shooter) == 0 or np.allclose(np.median(shooter, axis=0)[1:], [0.906, 1.0], atol=0.02)


def test04_clicks_pick_the_patch_under_them(demo):
    d = shown(demo, 0)
    left, top, w, h = d.layout["scene"]
    ys, xs = np.nonzero(d.ids == 2)                 # a pixel of the back wall, on the scene panel
    d.handle(("click", left + xs[len(xs) // 2], top + ys[len(ys) // 2]))
    assert d.patch == 2
    shown(d, 2)
    left, top, w, h = d.layout["items"]
    ys, xs = np.nonzero(d.cross_ids == 15 + 1)       # the light, as the back wall's hemicube sees it
    assert len(xs)
    y, x = ys[len(ys) // 2], xs[len(xs) // 2]
    d.handle(("click", left + x * w // d.cross_ids.shape[1], top + y * h // d.cross_ids.shape[0]))
    assert d.patch == 15
    left, top, w, h = d.layout["weights"]
    d.handle(("click", left + w // 2, top + h // 2))
    assert d.patch == 15, "the delta form factors are no patch"


def test05_keys_step_patches_and_change_settings(demo):
    d = shown(demo, 15)
    d.handle(("key", "right"))
    assert d.patch == 0, "→ wraps around"
    d.handle(("key", "left"))
    assert d.patch == 15
    shown(d, 0)
    fixed = d.painted_row().sum()
    d.handle(("key", "p"))
    shown(d, 0)
    assert not d.proximity and np.array_equal(d.painted_row(), d.shown.hemicube_row)
    assert d.painted_row().sum() != pytest.approx(fixed, abs=1e-3), "the floor's fix is large (it touches the walls)"
    d.handle(("key", "+"))
    shown(d, 0)
    assert d.resolution == 256 and d.shown.top.shape == (256, 256)
    d.handle(("key", "-"))
    d.handle(("key", "p"))
    shown(d, 0)
    assert d.resolution == 128 and d.painted_row().sum() == pytest.approx(fixed, abs=1e-12)


@pytest.mark.spawns
@needs_xvfb
def test06_the_window_shows_the_headless_frame(run, tmp_path):
    shot = tmp_path / "shot.png"
    done = cs451("demo", "hemicube", "--impl", str(run / "sub"), "--window", "--frames", "3", "--screenshot", str(shot),
                 display=True)
    assert done.returncode == 0, done.stderr[-2000:]
    window, frame = load_png(shot), load_png(run / "frames" / "hemicube-02.png")
    assert window.shape == frame.shape
    assert np.abs(window - frame).max() <= 1 / 255


LIVE = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    import glfw
    from cs451.demos import window as W
    from cs451.demos.player import play
    from cs451.impl import load_impl
    from cs451.stages.hemicube.demo import HemicubeDemo

    demo = HemicubeDemo(load_impl(Path(sys.argv[1]), "hemicube"))
    seen = {"patches": []}
    own_keys = W.Window.keys
    def keys(self):                     # polled more than once a frame: each event is sent once
        if self.frames == 3 and "right" not in seen:
            seen["right"] = True
            self._on_key(self.win, glfw.KEY_RIGHT, 0, glfw.PRESS, 0)
        if self.frames == 8 and "click" not in seen:
            seen["click"] = True
            ys, xs = (demo.ids == 2).nonzero()
            glfw.set_cursor_pos(self.win, xs[len(xs) // 2], ys[len(ys) // 2])
            self._on_click(self.win, glfw.MOUSE_BUTTON_LEFT, glfw.PRESS, 0)
        if self.frames == 14 and "title" not in seen:
            seen["title"] = glfw.get_window_title(self.win)
            self._on_key(self.win, glfw.KEY_ESCAPE, 0, glfw.PRESS, 0)
        if demo.shown is not None and (not seen["patches"] or seen["patches"][-1] != demo.shown.patch):
            seen["patches"].append(demo.shown.patch)
        seen["frames"] = self.frames
        return own_keys(self)
    W.Window.keys = keys
    play(demo, window=True, frames=500)
    print("RESULT " + json.dumps(seen))
""")


@pytest.mark.spawns
@needs_xvfb
def test07_a_live_window_answers_keys_and_clicks_and_escape_quits(tmp_path):
    seen = live_window_result(LIVE, KIT_ROOT / "reference" / "hemicube", tmp_path)
    assert seen["patches"] == [0, 1, 2], "patch 0, then → to 1, then a click on the back wall (2)"
    assert seen["frames"] < 100 and "← → patch" in seen["title"] and "p proximity fix (H6)" in seen["title"]
