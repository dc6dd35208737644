"""`cs451 demo whitted` (stage 2's demo): frames that refine and end on `cs451 render`'s image, switches that change
what the submission's W11 casts (its own counters say so), a pixel's ray tree that is what W11 cast, and the window
under Xvfb showing what the headless frame shows."""
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
from cs451.compare import compare_images
from cs451.demos.controls import help_keys
from cs451.demos.overlay import help_rect
from cs451.impl import load_impl
from cs451.imageio import load_png
from cs451.stages.whitted.demo import WhittedDemo, next_piece, progressive_order

from demo_windows import XVFB, live_window_result, needs_xvfb

REF = load_impl(KIT_ROOT / "reference" / "whitted", "whitted")
SIZE = "80x60"
W, H = 80, 60


def cs451(*args: str, display: bool = False, timeout: int = 300) -> subprocess.CompletedProcess:
    env = {k: v for k, v in os.environ.items() if display or k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    command = [*XVFB] if display else []
    return subprocess.run(command + [sys.executable, "-m", "cs451", *args], cwd=KIT_ROOT, env=env, capture_output=True,
                          text=True, timeout=timeout)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    """The headless demo and `cs451 render` on a copy of the reference in a folder of its own, as a submission."""
    root = tmp_path_factory.mktemp("whitted-demo")
    shutil.copytree(KIT_ROOT / "reference" / "whitted", root / "sub" / "whitted",
                    ignore=shutil.ignore_patterns("__pycache__"))
    demo = cs451("demo", "whitted", "--impl", str(root / "sub"), "--size", SIZE, "-o", str(root / "frames"))
    assert demo.returncode == 0, demo.stderr[-2000:]
    render = cs451("render", "whitted", "--impl", str(root / "sub"), "--size", SIZE, "-o", str(root / "render.png"))
    assert render.returncode == 0, render.stderr[-2000:]
    return root


def picture(frame: np.ndarray, zoom: int) -> np.ndarray:
    """The image part of a frame, one value per image pixel (the frame shows each as a zoom × zoom square)."""
    return frame[:H * zoom:zoom, :W * zoom:zoom]


@pytest.mark.spawns
def test01_frames_refine_coarse_to_fine_and_end_on_the_render(run):
    frames = sorted((run / "frames").glob("whitted-*.png"))
    with Image.open(run / "frames" / "whitted.gif") as gif:
        assert gif.n_frames == len(frames) == 10     # 4 passes, a ray tree, 4 switches off in turn, all back on
    first, last = load_png(frames[0]), load_png(frames[-1])
    zoom = first.shape[1] // W
    assert first.shape == last.shape and first.shape[0] > H * zoom, "a caption strip under the picture"
    coarse = picture(first, zoom)
    _, _, blocks = progressive_order(W, H)
    b = blocks[0]
    hx, hy, hw, hh = help_rect((W * zoom, H * zoom), help_keys("whitted"), WhittedDemo.caption_lines)
    seen, checked = set(), 0
    for y in range(0, H, b):                              # the first pass: one pixel traced per block, painted over it
        for x in range(0, W, b):
            if x * zoom < hx + hw and y * zoom < hy + hh:
                continue                                  # under the help panel (up until the first key)
            block = coarse[y:y + b, x:x + b]
            assert np.all(block == coarse[y, x])
            seen |= {tuple(c) for c in block.reshape(-1, 3)}
            checked += 1
    assert checked >= 10 and len(seen) <= checked
    target = load_png(run / "render.png")
    verdict = compare_images(target, picture(last, zoom))
    assert verdict.passed, verdict.message
    assert verdict.max_error <= 1 / 255, "the same rays through the same W11, in pieces: the same colours"


def test02_switches_change_what_w11_casts():
    demo = WhittedDemo(REF, "whitted", (40, 30))

    def finish(*keys: str) -> dict[str, int]:
        for key in keys:
            demo.handle(("key", key))
        while demo.busy():
            demo.step(0.05)
        return dict(demo.render.scene.counters)

    base = finish()
    image = demo.image().copy()
    assert base["camera"] == 40 * 30 and min(base["shadow"], base["reflection"], base["transmission"]) > 0
    unshadowed = finish("s")
    assert unshadowed["shadow"] == 0 and unshadowed["camera"] == base["camera"]
    assert demo.image().mean() > image.mean(), "without shadow rays every point is lit: a brighter picture"
    unreflected = finish("s", "r")
    assert unreflected["shadow"] > 0 and unreflected["reflection"] < base["reflection"] / 4
    unrefracted = finish("r", "t")
    assert unrefracted["transmission"] == 0
    uncut = finish("t", "c")
    assert uncut["reflection"] + uncut["transmission"] > base["reflection"] + base["transmission"]
    shallow = finish("c", "-", "-", "-", "-", "-", "-")
    assert demo.settings.depth == 0 and shallow["reflection"] == shallow["transmission"] == 0
    again = finish(*"++++++")
    assert again == base and np.array_equal(demo.image(), image), "back to the start: the finished picture, kept"


def test03_the_ray_tree_is_what_w11_cast_for_that_pixel():
    demo = WhittedDemo(REF, "whitted", (40, 30))
    x, y = demo.default_pixel()
    demo.handle(("click", x * demo.zoom + 1, y * demo.zoom + 1))
    tree = demo.tree
    assert tree is not None and tree.pixel == (x, y)
    assert tree.rays[0].kind == "camera" and tree.rays[0].hit
    c = tree.counters
    assert (c["camera"], c["reflection"], c["transmission"], c["shadow"]) == (
        1, tree.count("reflection"), tree.count("refraction"), len(tree.shadows))
    assert tree.count("refraction") >= 2, "the default pixel looks into the glass sphere"
    for ray in tree.rays[1:]:
        assert ray.parent is not None and ray.kind in ("reflection", "refraction")
        assert np.linalg.norm(ray.start - tree.rays[ray.parent].end) < 1e-6
    p = demo.camera.point(tree.rays[0].end)        # the first hit is drawn where the pixel is
    assert p is not None and abs(p[0] - (x + 0.5)) < 0.05 and abs(p[1] - (y + 0.5)) < 0.05
    with_tree = demo.frame()
    demo.handle(("key", "s"))
    assert demo.tree.shadows == [] and demo.tree.counters["shadow"] == 0
    demo.handle(("key", "x"))
    assert demo.tree is None and not np.array_equal(demo.frame(), with_tree)


@pytest.mark.spawns
@needs_xvfb
def test04_the_window_shows_the_headless_frame(run, tmp_path):
    shot = tmp_path / "shot.png"
    done = cs451("demo", "whitted", "--impl", str(run / "sub"), "--size", SIZE, "--window", "--screenshot", str(shot),
                 display=True)
    assert done.returncode == 0, done.stderr[-2000:]
    window, frame = load_png(shot), load_png(sorted((run / "frames").glob("whitted-*.png"))[-1])
    assert window.shape == frame.shape
    assert np.abs(window - frame).max() <= 1 / 255


#: Runs the demo in a live window; presses s, clicks a pixel and presses q through the window's own callbacks.
LIVE = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    import glfw
    from cs451.demos import window as W
    from cs451.demos.player import play
    from cs451.impl import load_impl
    from cs451.stages.whitted.demo import WhittedDemo

    demo = WhittedDemo(load_impl(Path(sys.argv[1]), "whitted"), "whitted", (40, 30))
    x, y = demo.default_pixel()
    seen = {}
    own_keys = W.Window.keys
    def keys(self):                     # polled more than once a frame: each event is sent once
        if self.frames == 2 and "sent" not in seen:
            seen["sent"] = True
            self._on_key(self.win, glfw.KEY_S, 0, glfw.PRESS, 0)
            glfw.set_cursor_pos(self.win, x * demo.zoom + 2, y * demo.zoom + 2)
            self._on_click(self.win, glfw.MOUSE_BUTTON_LEFT, glfw.PRESS, 0)
        if self.frames == 30 and "title" not in seen:
            seen["title"] = glfw.get_window_title(self.win)
            self._on_key(self.win, glfw.KEY_Q, 0, glfw.PRESS, 0)
        seen["frames"] = self.frames
        return own_keys(self)
    W.Window.keys = keys
    play(demo, window=True, frames=500)
    seen.update(shadows=demo.settings.shadows, pixel=demo.tree.pixel if demo.tree else None, want=[x, y])
    print("RESULT " + json.dumps(seen))
""")


@pytest.mark.spawns
@needs_xvfb
def test05_a_live_window_answers_keys_and_clicks_and_q_quits(tmp_path):
    seen = live_window_result(LIVE, KIT_ROOT / "reference" / "whitted", tmp_path)
    assert seen["shadows"] is False, "s switched the shadows off"
    assert seen["pixel"] == seen["want"], "the click drew that pixel's tree"
    assert seen["frames"] < 100, "q closed the window"
    assert "s shadows" in seen["title"] and "click a pixel's ray tree" in seen["title"], seen["title"]


@pytest.mark.spawns
@pytest.mark.parametrize("args, option", [
    (["whitted", "--frames", "0"], "--frames"),
    (["whitted", "--no-window", "--screenshot", "x.png"], "--screenshot"),
    (["whitted", "--size", "80"], "--size"),
    (["sphere", "--scene", "whitted"], "--scene"),
    (["whitted", "--scene", "no-such-scene"], "no-such-scene"),
])
def test06_bad_options_are_one_line_naming_the_option(args, option, tmp_path):
    done = cs451("demo", *args, "-o", str(tmp_path), timeout=120)
    assert done.returncode == 2 and option in done.stderr and done.stderr.count("\n") == 1, done.stderr


@pytest.mark.spawns
def test07_the_starter_stops_at_its_first_unwritten_task_in_one_line(tmp_path):
    done = cs451("demo", "whitted", "--impl", "starter", "--size", SIZE, "-o", str(tmp_path), timeout=120)
    assert done.returncode == 2 and "W1 camera_rays() is not implemented yet" in done.stderr
    assert done.stderr.count("\n") == 1


@pytest.mark.spawns
@pytest.mark.slow
def test08_full_size_demo_ends_on_cs451_render(tmp_path):
    """At the scene's own size `cs451 render` traces one large batch, the demo pieces sized by time (both through the
    reference's compiled frame once the camera rays have thrown its switch): the last frame matches the render."""
    assert cs451("demo", "whitted", "-o", str(tmp_path / "frames"), timeout=900).returncode == 0
    assert cs451("render", "whitted", "-o", str(tmp_path / "render.png"), timeout=900).returncode == 0
    last = load_png(sorted((tmp_path / "frames").glob("whitted-*.png"))[-1])
    target = load_png(tmp_path / "render.png")
    zoom = last.shape[1] // target.shape[1]
    verdict = compare_images(target, last[:target.shape[0] * zoom:zoom, :target.shape[1] * zoom:zoom])
    assert verdict.passed, verdict.message


def test09_pieces_grow_past_a_fixed_overhead_and_fit_a_proportional_cost():
    assert next_piece((100, 0.030), None, 0.02, 10**6) == 66, "one piece, no fit yet: the proportional guess"
    assert next_piece((200, 0.031), (100, 0.030), 0.02, 10**6) == 400, "the overhead alone is over the target: double"
    assert abs(next_piece((1000, 0.010), (500, 0.005), 0.02, 10**6) - 2000) <= 1, "proportional: the target's worth"
    assert next_piece((1000, 0.010), (500, 0.005), 0.02, 1500) == 1500 and next_piece((50, 1.0), None, 0.02, 99) == 16


def test10_a_compiled_size_refines_through_the_compiled_frame_and_the_switches_still_reach_w7(monkeypatch):
    """At 160 × 120 the camera rays are a large batch, so the reference's W11 runs its compiled frame (which calls
    neither W5 nor W7) on every piece; while the shadow switch or the ray tree replaces W7 or W5 it must call them."""
    import importlib
    frame = importlib.import_module("cs451.stages.whitted.accel.frame")
    whole, used = frame.trace_frame, []
    monkeypatch.setattr(frame, "trace_frame", lambda *a, **k: used.append(len(a[1])) or whole(*a, **k))
    demo = WhittedDemo(REF, "whitted", (160, 120))
    while demo.busy():
        demo.step(0.05)
    lit = demo.image().copy()
    assert sum(used) == 160 * 120 and demo.render.scene.counters["shadow"] > 0, "every pixel through the compiled frame"
    x, y = demo.default_pixel()
    demo.handle(("click", x * demo.zoom + 1, y * demo.zoom + 1))
    assert demo.tree.count("refraction") >= 2 and demo.tree.shadows, "the tree is recorded from W5 and W7's calls"
    used.clear()
    demo.handle(("key", "s"))
    while demo.busy():
        demo.step(0.05)
    assert used == [] and demo.render.scene.counters["shadow"] == 0 and demo.image().mean() > lit.mean()
    assert demo.tree.shadows == []


def test15_the_demo_and_the_deck_build_one_pixels_tree_alike():
    """One tree builder (ray_tree.build_tree): the demo's tree of a pixel (its W11 through the stage, recorded) and
    the deck's (the reference's render probe, recorded as the grader records it) hold the same rays, kinds and
    parents, and the same shadow rays."""
    import json
    from cs451.scene import BUNDLED_DIR
    from cs451.stages.whitted.figure_rays import ray_tree
    demo = WhittedDemo(REF, "whitted", (40, 30))
    x, y = demo.default_pixel()
    tree = demo.ray_tree(x, y)
    deck = ray_tree(json.loads((BUNDLED_DIR / "whitted.json").read_text()), [(x, y)], (40, 30))
    drawn = [r for r in deck if r["kind"] != "shadow"]
    assert tree.count("reflection") > 0 and tree.count("refraction") > 0
    assert [(r.kind, r.parent, r.hit) for r in tree.rays] == [(r["kind"], r["parent"], r["hit"]) for r in drawn]
    assert all(np.allclose(r.end, d["end"]) for r, d in zip(tree.rays, drawn) if r.hit)   # misses: each its own reach
    assert len(tree.shadows) == sum(r["kind"] == "shadow" for r in deck) > 0
