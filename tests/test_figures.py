"""The handouts' target images are the reference's renders of the public image tests, and stay so."""
from __future__ import annotations

import pytest

from cs451 import KIT_ROOT
from cs451.packaging.figures import check_figures, stage_figures
from cs451.packaging.release import build_release
from cs451.stages import get_stage, stage_names


@pytest.mark.spawns
@pytest.mark.parametrize("stage", stage_names())
def test_the_handout_figures_are_in_step_with_the_reference(stage):
    assert check_figures(stage) == [], "run `cs451 figures` to regenerate them"


def test_every_public_image_test_has_a_figure_and_a_release_ships_them(tmp_path):
    figures = stage_figures("sphere", show_progress=False)
    assert [f.test.task for f in figures] == ["S5", "S5", "S5", "S5", "S6", "S6", "S6"]
    out = build_release("sphere", tmp_path / "repo")
    handout = out / "assignments" / get_stage("sphere").handout
    assert sorted(p.name for p in (handout / "figures").glob("*.png")) == sorted(f.name for f in figures)
    assert "![S5.1](figures/S5.1.png)" in (handout / "README.md").read_text()


def test_a_changed_figure_is_drift(tmp_path, monkeypatch):
    import numpy as np
    from cs451.imageio import load_png, save_png
    import cs451.packaging.figures as F
    kit = tmp_path / "kit"
    handout = KIT_ROOT / "assignments" / get_stage("sphere").handout
    (kit / "assignments").mkdir(parents=True)
    import shutil
    shutil.copytree(handout, kit / "assignments" / handout.name)
    path = kit / "assignments" / handout.name / "figures" / "S5.1.png"
    image = load_png(path)
    save_png(path, np.clip(image * 0.7, 0, 1))
    monkeypatch.setattr(F, "KIT_ROOT", kit)
    assert check_figures("sphere") == [f"assignments/{handout.name}/figures/S5.1.png: differs from the reference's render"]


def test_the_handout_diagrams_are_in_step_ship_and_a_changed_one_is_drift(tmp_path, monkeypatch):
    """Stage 1's explanatory pictures (where the light is, the modelview order): drawn by the reference, shipped."""
    import shutil

    import numpy as np

    import cs451.packaging.diagrams as D
    from cs451.imageio import load_png, save_png
    handout = KIT_ROOT / "assignments" / get_stage("sphere").handout
    assert D.check_diagrams("sphere") == []
    text = (handout / "README.md").read_text()
    for name in get_stage("sphere").diagrams():
        assert f"](diagrams/{name})" in text, f"the handout does not show {name}"
    out = build_release("sphere", tmp_path / "repo")
    shipped = out / "assignments" / handout.name / "diagrams"
    assert sorted(p.name for p in shipped.glob("*.png")) == sorted(get_stage("sphere").diagrams())
    kit = tmp_path / "kit"
    shutil.copytree(handout, kit / "assignments" / handout.name)
    path = kit / "assignments" / handout.name / "diagrams" / "light-spaces.png"
    save_png(path, np.flip(load_png(path), axis=1))   # the two panels swapped: the light on the wrong side
    monkeypatch.setattr(D, "KIT_ROOT", kit)
    assert D.check_diagrams("sphere") == [f"assignments/{handout.name}/diagrams/light-spaces.png: differs from the "
                                          f"reference's render"]


@pytest.mark.spawns
def test_a_figure_drawn_with_render_figure_matches_it_and_the_starter_says_what_is_missing(tmp_path):
    """The handout's recipe: `cs451 render --figure` draws the figure's own test (S5.3's lights and S6.2's coarse
    sphere are in no bundled scene; R5.6's patch size and resolution are the test's), and compare judges it."""
    import subprocess
    import sys
    for number, handout in (("S5.3", "01-sphere"), ("S6.2", "01-sphere"), ("R5.6", "04-radiosity")):
        mine = tmp_path / f"{number}.png"
        cs451 = [sys.executable, "-m", "cs451"]
        done = subprocess.run(cs451 + ["render", "--figure", number, "-o", str(mine), "--impl", "reference"],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 0, done.stderr
        done = subprocess.run(cs451 + ["compare", str(mine), f"assignments/{handout}/figures/{number}.png", "-o",
                                       str(tmp_path / "c.png")], cwd=KIT_ROOT, capture_output=True, text=True)
        assert done.returncode == 0 and " matches " in done.stdout, done.stdout + done.stderr
        done = subprocess.run(cs451 + ["render", "--figure", number, "-o", str(mine), "--impl", "starter"],
                              capture_output=True, text=True, timeout=600)
        assert done.returncode == 2 and "is not implemented yet" in done.stderr and "Traceback" not in done.stderr
