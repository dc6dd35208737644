"""`cs451 demo radiosity` (stage 4's demo, issue 37): the submission's own R3 run a shot at a time, paused (space),
stepped (n, →), started again (r); flat patches or Gouraud (g), the ambient preview (a); the patch that just shot
outlined in the picture, the unshot energy as a number and a bar; and the keys through a live window under Xvfb."""
from __future__ import annotations

import textwrap
import threading
import types

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.errors import KitError
from cs451.impl import load_impl
from cs451.stages.radiosity.solvers import energy
from cs451.stages import radiosity as R
from cs451.stages.radiosity.stepping import THREAD_NAME
from cs451.stages.radiosity.demo import SHOOTER, RadiosityDemo, percent

from demo_windows import live_window_result, needs_xvfb

REF = load_impl(KIT_ROOT / "reference" / "radiosity", "radiosity")


def loops() -> int:
    return sum(t.name == THREAD_NAME and t.is_alive() for t in threading.enumerate())


def run(d: RadiosityDemo) -> RadiosityDemo:
    while d.busy():
        d.step(0.05)
    return d


@pytest.fixture(scope="module")
def box():
    d = RadiosityDemo(REF, "cornell-box", (96, 96))
    d.ready()
    yield d
    d.close()


def test01_space_pauses_n_shoots_one_and_r_starts_again(box):
    d = box
    d.handle(("key", "r"))
    d.handle(("key", "space"))
    assert d.paused and run(d).shots == 0 and d.shooter is None, "paused before the first shot"
    emitted = d.unshot()
    d.handle(("key", "n"))
    assert run(d).shots == 1 and d.paused
    first = d.shooter
    assert d.patches.labels[d.patches.parent[first]].startswith("lights"), "the light shoots first"
    assert d.shot_power == pytest.approx(float(np.abs(d.patches.emission[first]).sum() * d.patches.areas[first])
                                         / energy(d.patches.emission, d.patches.areas))
    assert d.unshot() < emitted
    d.handle(("key", "right"))
    assert run(d).shots == 2 and d.shooter != first
    d.handle(("key", "r"))
    assert d.shots == 0 and d.shooter is None and np.array_equal(d.B, d.patches.emission) and d.paused
    assert loops() == 0, "the dropped loop's thread has ended"
    d.handle(("key", "n"))
    assert run(d).shots == 1 and d.shooter == first, "the same loop from the start: the same first shot"
    assert loops() == 1


def test02_g_and_a_change_what_is_drawn(box):
    d = box
    d.handle(("key", "r"))
    for _ in range(3):                             # paused after 3 shots: the light's, ambient on
        d.handle(("key", "n"))
        run(d)
    gouraud_ambient = d.frame().copy()
    assert np.allclose(d.display(), d.B + d.patches.reflectance * d.calls.ambient(d.patches.areas,
                                                                               d.patches.reflectance, d.dB))
    d.handle(("key", "a"))
    assert not d.ambient and np.array_equal(d.display(), d.B)
    assert d.frame()[:96].mean() < gouraud_ambient[:96].mean(), "without the ambient preview: B alone, darker"
    d.handle(("key", "a"))
    d.handle(("key", "g"))
    assert d.flat and not np.array_equal(d.frame(), gouraud_ambient)
    assert "flat patches" in d.caption() and "B + ρ·ambient" in d.caption()
    d.handle(("key", "g"))
    assert np.array_equal(d.frame(), gouraud_ambient) and "Gouraud (R5)" in d.caption()


def test03_the_shot_is_outlined_and_the_energy_left_is_a_number_and_a_bar(box):
    d = box
    d.handle(("key", "r"))
    run(d)
    assert not np.all(d.frame()[:96] == SHOOTER, axis=2).any(), "no shot yet: nothing outlined"
    d.handle(("key", "n"))
    run(d)
    frame = d.frame()
    ys, xs = np.nonzero(np.all(frame[:96] == SHOOTER, axis=2))
    corners = np.array(d._projected(d.patches.quads[d.shooter]))
    assert len(xs) > 5 and corners[:, 0].min() - 3 <= xs.min() and xs.max() <= corners[:, 0].max() + 3
    assert corners[:, 1].min() - 3 <= ys.min() and ys.max() <= corners[:, 1].max() + 3, "around the shooter"
    caption = d.caption()
    assert f"shot 1 (paused): patch {d.shooter} (lights[0])" in caption
    assert f"unshot energy {percent(d.unshot())}" in caption
    bar = frame[96 + d.bar // 2]
    filled = int(np.all(bar == (255, 170, 40), axis=1).sum())
    assert filled == round(96 * d.unshot()) and 0 < filled < 96


def test04_resumed_it_runs_the_submissions_loop_to_its_end():
    d = RadiosityDemo(REF, "furnace", (32, 32))
    run(d)
    assert d.done and d.unshot() <= d.opts.tolerance * (1 + 1e-9)
    p, o = d.patches, d.opts
    sol = R.solve_progressive(REF, d.rows, p.areas, p.reflectance, p.emission, o.tolerance, o.max_shots, o.overshoot)
    assert d.shots == sol.steps and np.array_equal(d.B, sol.radiosity), "R3's own answer, a shot at a time"
    assert np.allclose(d.B, 2.0, atol=0.05), "the white furnace: E / (1 - ρ) = 2, to the hemicubes' error"
    assert "converged" in d.caption()
    d.handle(("key", "r"))
    d.handle(("key", "a"))
    assert np.allclose(d.display(), p.emission)
    d.handle(("key", "a"))
    assert np.allclose(d.display(), 2.0, rtol=1e-6), "before any shot, B + ρ·ambient is already the furnace's answer"


def test05_an_error_in_the_loop_is_the_submissions_one_line():
    broken = types.ModuleType("broken")
    broken.__dict__.update({k: v for k, v in vars(REF).items() if not k.startswith("__")})

    def progressive_refinement(*args):
        raise NotImplementedError("R3: not yet")
    broken.progressive_refinement = progressive_refinement
    d = RadiosityDemo(broken, "furnace", (32, 32))
    with pytest.raises(KitError, match="R3 progressive_refinement\\(\\) is not implemented yet"):
        run(d)
    d.close()


#: A live window: space, n, n, g, a, r through the window's own key callback, then q.
LIVE = textwrap.dedent("""
    import json, sys
    from pathlib import Path
    import glfw
    from cs451.demos import window as W
    from cs451.demos.player import play
    from cs451.impl import load_impl
    from cs451.stages.radiosity.demo import RadiosityDemo

    demo = RadiosityDemo(load_impl(Path(sys.argv[1]), "radiosity"), "cornell-box", (64, 64))
    seen = {}
    keys_at = {1: "SPACE", 3: "N", 5: "N", 7: "G", 9: "A", 12: "R", 15: "Q"}
    own_keys = W.Window.keys
    def keys(self):
        key = keys_at.pop(self.frames, None)
        if key == "R":
            seen["before"] = {"shots": demo.shots, "paused": demo.paused, "flat": demo.flat, "ambient": demo.ambient,
                              "help": self.help_shown, "caption": self.caption}
        if key is not None:
            self._on_key(self.win, getattr(glfw, "KEY_" + key), 0, glfw.PRESS, 0)
        return own_keys(self)
    W.Window.keys = keys
    play(demo, window=True, frames=400)
    seen["after"] = {"shots": demo.shots, "paused": demo.paused}
    demo.close()
    print("RESULT " + json.dumps(seen))
""")


@pytest.mark.spawns
@needs_xvfb
def test06_the_keys_reach_it_in_a_live_window(tmp_path):
    seen = live_window_result(LIVE, KIT_ROOT / "reference" / "radiosity", tmp_path)
    before = seen["before"]
    assert before["paused"] and before["flat"] and not before["ambient"] and not before["help"]
    assert before["shots"] >= 2 and f"shot {before['shots']} (paused)" in before["caption"]
    assert seen["after"] == {"shots": 0, "paused": True}, "r: from the start, still paused"
