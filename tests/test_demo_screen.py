"""Every demo on the screen (issue 37): its caption and help drawn into the headless frames, text readable from the back
row at 1080p, --scene and --size for every stage (a scene a stage cannot draw refused in one line naming the stages
that can), and, under Xvfb, the window going full screen and back, the picture rescaled (letterboxed) on a resize, and
the help panel answering h, ? and the first key."""
from __future__ import annotations

import os
import subprocess
import sys
import textwrap

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.demos import overlay, run_demo
from cs451.demos.controls import help_keys
from cs451.imageio import load_png
from cs451.stages import stage_names

from demo_windows import XVFB, live_window_result, needs_xvfb

#: Per stage: a scene other than its default, a picture size, and the picture's width in the frames it writes.
OTHER = {
    "sphere": ("orrery", "400x300", 400),
    "whitted": ("cornell-spheres", "64x48", 640),
    "hemicube": ("furnace", "200x150", 500),
    "radiosity": ("furnace", "240x180", 240),
    "pathtrace": ("room", "48x36", 528),
}


def cs451(*args: str, display: bool = False, timeout: int = 300) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if display or k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    return subprocess.run(([*XVFB] if display else []) + [sys.executable, "-m", "cs451", *args], cwd=KIT_ROOT, env=env,
                          capture_output=True, text=True, timeout=timeout)


def help_drawn(frame: np.ndarray, picture: tuple[int, int], stage: str, lines: int) -> float:
    """The share of the help panel's opaque pixels (its letters' cores) that the frame shows in their colours."""
    x, y, panel = overlay.help_layer(picture, help_keys(stage), lines)
    core = panel[..., 3] >= 250
    shown = np.round(frame[y:y + panel.shape[0], x:x + panel.shape[1]] * 255).astype(int)
    assert core.sum() > 100
    return float(np.all(np.abs(shown[core] - panel[..., :3][core]) <= 6, axis=1).mean())


@pytest.mark.parametrize("stage", stage_names())    # a stage missing from OTHER fails here
def test01_every_demo_takes_scene_and_size_and_draws_its_caption_and_help_into_the_frames(stage, tmp_path):
    assert stage in OTHER, f"stage {stage}: no case in OTHER (a scene other than its demo's, a size, the frame width)"
    scene, size, width = OTHER[stage]
    paths = run_demo(stage=stage, output=tmp_path, window=False, scene=scene, size=size)
    frames = sorted(tmp_path.glob(f"{scene if stage == 'sphere' else stage}-[0-9][0-9].png"))
    assert len(frames) >= 2 and paths, [p.name for p in paths]
    first, last = load_png(frames[0]), load_png(frames[-1])
    assert first.shape[1] == width, "--size: the picture's size"
    w, h = (int(v) for v in size.split("x"))
    picture = (width, h * width // w + (max(10, h // 24) if stage == "radiosity" else 0))   # radiosity: and its bar
    if stage == "hemicube":
        picture = (width, h + h // 2)                                                        # and the five views
    band = first[picture[1]:]
    assert (band > 0.5).all(axis=2).sum() > 50, "the caption's text, light on the dark band under the picture"
    lines = (first.shape[0] - picture[1]) // overlay.line_height(overlay.MIN_PX)
    assert help_drawn(first, picture, stage, lines) == 1.0, "the help panel over the first frame"
    assert help_drawn(last, picture, stage, lines) < 0.5, "hidden from the first key on, as in the window"


def test02_text_is_at_least_24_px_at_1080p_and_never_a_missing_glyph():
    px = overlay.text_px(1080)
    assert px >= 24 and overlay.font(px).size >= 24 and overlay.line_height(px) >= 32
    band = overlay.band_image(1920, "Hg shot 12 — unshot energy 3.1% · ρ·ambient, 32×16", 1, px)
    rows = np.nonzero((band[..., :3] > 200).any(axis=(1, 2)))[0]
    assert rows.max() - rows.min() + 1 >= 24, "from the top of H to the foot of g"
    assert overlay.plain("32×16 — ρ·ambient …") == "32x16 - rho·ambient …"
    fancy = overlay.band_image(600, "β ≤ 0.1 → ×", 1, 24)
    spelt = overlay.band_image(600, "beta <= 0.1 -> x", 1, 24)
    assert np.array_equal(fancy, spelt)


def test03_a_composed_frame_is_the_picture_the_band_and_the_help_where_help_rect_says():
    picture = np.full((300, 400, 3), 90, np.uint8)
    keys = help_keys("whitted")
    with_help = overlay.compose(picture, "one\ntwo", 2, keys, True)
    without = overlay.compose(picture, "one\ntwo", 2, keys, False)
    assert with_help.shape == without.shape == (300 + overlay.band_height(2, 24), 400, 3)
    assert np.array_equal(without[:300], picture), "the caption goes under the picture, not over it"
    x, y, w, h = overlay.help_rect((400, 300), keys, 2)
    changed = np.nonzero(np.any(with_help != without, axis=2))
    assert changed[0].min() >= y and changed[0].max() < y + h and changed[1].min() >= x and changed[1].max() < x + w


@pytest.mark.spawns
@pytest.mark.parametrize("stage, scene, able", [("sphere", "whitted", "whitted"), ("radiosity", "orrery", "sphere"),
                                                ("hemicube", "rippled-torus", "whitted")])
def test04_a_scene_the_demo_cannot_draw_is_one_line_naming_the_demos_that_can(stage, scene, able, tmp_path):
    done = cs451("demo", stage, "--scene", scene, "-o", str(tmp_path), timeout=120)
    assert done.returncode == 2 and done.stderr.count("\n") == 1, done.stderr
    assert f"--scene {scene}: the {stage} demo cannot draw it" in done.stderr
    assert done.stderr.strip().endswith(f"the demos that can: {able}"), done.stderr


@pytest.mark.spawns
def test05_the_help_lists_every_key_and_the_windows_own():
    for stage in stage_names():
        keys = [k for k, _ in help_keys(stage)]
        assert "f" in keys and "h ?" in keys and any(k.split()[0] == "q" for k in keys), (stage, keys)
    assert [k for k, _ in help_keys("radiosity")][:5] == ["space", "n →", "r", "g", "a"]
    assert "every demo" in cs451("demo", "--help").stdout


#: A live pathtrace window under a 1920x1080 Xvfb screen: f, a resize, h, ?, and a key, through the window's callbacks.
LIVE = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    import glfw
    from cs451.demos import window as W
    from cs451.demos.player import play
    from cs451.impl import load_impl
    from cs451.stages.pathtrace.demo import PathDemo

    demo = PathDemo(load_impl(Path(sys.argv[1]), "pathtrace"), "cornell-box", (64, 48))
    seen = {}
    def record(self, name):
        seen[name] = {"size": self.size(), "placed": self._placed, "full": self.fullscreen, "help": self.help_shown,
                      "window": glfw.get_window_size(self.win)}
    steps = {2: "start", 4: "f", 8: "full", 9: "f", 13: "back", 14: "resize", 18: "resized", 19: "h", 20: "hidden",
             21: "?", 22: "shown", 23: "r", 24: "keyed", 25: "q"}
    own_keys = W.Window.keys
    def keys(self):                     # polled more than once a frame: each event is sent once
        what = steps.pop(self.frames, None)
        if what in ("f", "h", "r", "q"):
            self._on_key(self.win, getattr(glfw, "KEY_" + what.upper()), 0, glfw.PRESS, 0)
        elif what == "?":
            self._on_key(self.win, glfw.KEY_SLASH, 0, glfw.PRESS, glfw.MOD_SHIFT)
        elif what == "resize":
            glfw.set_window_size(self.win, 600, 400)
        elif what is not None:
            record(self, what)
        return own_keys(self)
    W.Window.keys = keys
    play(demo, window=True, frames=400)
    seen["passes"] = demo.passes
    print("RESULT " + json.dumps(seen))
""")


@pytest.mark.spawns
@needs_xvfb
def test06_f_goes_full_screen_and_back_and_the_picture_keeps_its_shape_at_any_size(tmp_path, monkeypatch):
    monkeypatch.setattr("demo_windows.XVFB", ["xvfb-run", "-a", "-s", "-screen 0 1920x1080x24"])
    seen = live_window_result(LIVE, KIT_ROOT / "reference" / "pathtrace", tmp_path)
    start, full, back, resized = (seen[k] for k in ("start", "full", "back", "resized"))
    assert not start["full"] and full["full"] and not back["full"]
    assert tuple(full["size"]) == (1920, 1080), "the whole monitor"
    assert tuple(back["window"]) == tuple(start["window"]), "and back to the window it was"
    for state in (start, full, back, resized):
        left, top, w, h, scale = state["placed"]
        assert (w, h) == (512, 384) and left >= 0 and top >= 0
        assert left + w * scale <= state["size"][0] + 1 and top + h * scale <= state["size"][1] + 1
    assert start["placed"][4] == 1.0 and full["placed"][4] > 2.0, "the picture grows with the screen"
    left, top, w, h, scale = full["placed"]
    assert left > 100 and abs(left - (1920 - w * scale) / 2) <= 1, "letterboxed: centred, its shape kept"
    left, top, w, h, scale = resized["placed"]
    band = overlay.band_height(1, overlay.MIN_PX)
    assert tuple(resized["window"]) == (600, 400) and scale == pytest.approx((400 - band) / 384) and left > 0
    assert start["help"] and not seen["hidden"]["help"] and seen["shown"]["help"] and not seen["keyed"]["help"]
