"""The CLI as a user runs it: help for every subcommand, render, starter check, headless demo, bench."""
from __future__ import annotations

import subprocess
import sys

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.cli import build_parser, main
from cs451.imageio import load_png


def cs451(*args, env=None):
    return subprocess.run([sys.executable, "-m", "cs451.cli", *args], capture_output=True, text=True, env=env)


@pytest.mark.spawns
@pytest.mark.parametrize("command", ["render", "grade", "compare", "figures", "starter", "demo", "scenes", "bench"])
def test01_every_subcommand_has_help(command):
    proc = cs451(command, "--help")
    assert proc.returncode == 0 and "usage: cs451 " + command in proc.stdout


def test02_render_writes_the_sphere(tmp_path):
    out = tmp_path / "sphere.png"
    assert main(["render", "sphere", "-o", str(out)]) == 0
    img = load_png(out)
    assert img.shape == (500, 500, 3)
    assert img[0, 0].sum() == 0                       # black background
    centre = img[250, 250]
    assert centre[1] > centre[0] and centre[1] > centre[2]   # the sphere is green
    small = tmp_path / "small.png"
    assert main(["render", "sphere", "-o", str(small), "--size", "320x200", "--shading", "phong"]) == 0
    assert load_png(small).shape == (200, 320, 3)


@pytest.mark.spawns
def test03_render_with_the_starter_says_what_to_do(tmp_path):
    proc = cs451("render", "sphere", "-o", str(tmp_path / "x.png"), "--impl", "starter")
    assert proc.returncode == 2 and "not implemented yet" in proc.stderr and "Traceback" not in proc.stderr


@pytest.mark.spawns
@pytest.mark.parametrize("args, message", [
    (["render", "sphere", "-o", "x.png", "--size", "big"], "--size: expected WIDTHxHEIGHT"),
    (["render", "sphere", "-o", "x.png", "--impl", "/no/such/folder"], "submission folder not found"),
    (["grade", "sphere", "--submission", "/no/such/folder"], "submission folder not found"),
])
def test04_bad_arguments_get_one_line(args, message, tmp_path):
    proc = subprocess.run([sys.executable, "-m", "cs451.cli", *args], capture_output=True, text=True, cwd=tmp_path)
    assert proc.returncode == 2 and message in proc.stderr and proc.stderr.count("\n") == 1


@pytest.mark.spawns
def test05_starter_check_passes():
    assert cs451("starter", "--check").returncode == 0


@pytest.mark.spawns
def test06_demo_without_a_display_writes_images(tmp_path):
    env = {k: v for k, v in __import__("os").environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    proc = cs451("demo", "sphere", "-o", str(tmp_path), env=env)
    assert proc.returncode == 0, proc.stderr
    gouraud, phong = load_png(tmp_path / "sphere-gouraud.png"), load_png(tmp_path / "sphere-phong.png")
    assert gouraud.shape == phong.shape == (500, 500, 3)
    assert 0 < np.abs(gouraud - phong).max() < 0.1   # the same sphere, lit per vertex and per fragment
    assert load_png(tmp_path / "sphere-wide.png").shape == (400, 800, 3)


@pytest.mark.spawns
def test07_parser_lists_the_stages():
    assert "sphere" in build_parser()._subparsers._group_actions[0].choices["render"].format_help()
    assert any(line.startswith("sphere") for line in cs451("scenes").stdout.splitlines())


@pytest.mark.spawns
def test_compare_puts_a_render_beside_its_target_and_judges_it_as_the_tests_do(tmp_path):
    from cs451.imageio import load_png
    target = KIT_ROOT / "assignments" / "01-sphere" / "figures" / "S5.1.png"
    done = cs451("render", "sphere", "-o", str(tmp_path / "mine.png"))
    assert done.returncode == 0, done.stderr
    done = cs451("compare", str(tmp_path / "mine.png"), str(target), "-o", str(tmp_path / "side.png"))
    assert done.returncode == 0 and "matches" in done.stdout and "FLIP 0.000" in done.stdout, done.stdout
    side = load_png(tmp_path / "side.png")
    assert side.shape == (500 + 16, 4 * 500 + 3 * 4, 3)
    done = cs451("compare", str(tmp_path / "mine.png"), str(target.with_name("S5.2.png")))
    assert done.returncode == 2 and done.stderr.count("\n") == 1 and "--size 320x240" in done.stderr


@pytest.mark.spawns
def test_bench_sphere_writes_its_table_and_the_plot_the_readme_promises(tmp_path):
    done = cs451("bench", "sphere", "--quick", "-o", str(tmp_path))
    assert done.returncode == 0, done.stderr[-1500:]
    assert (tmp_path / "sphere.json").is_file() and load_png(tmp_path / "sphere.png").shape[2] == 3


def test_demo_captions_never_draw_a_missing_glyph_box():
    from cs451.demos.frames import captioned
    frame = np.zeros((60, 400, 3), np.uint8)
    fancy = captioned(frame, "16 shots — left: B, right: B + ρ·ambient, β ≤ 0.1")
    plain = captioned(frame, "16 shots - left: B, right: B + rho*ambient, beta <= 0.1")
    assert np.array_equal(fancy, plain)


def test_render_asks_the_stages_which_one_draws_a_scene(tmp_path, capsys):
    """Without --stage: the stage the scene's options name among those that draw it; none named, the first that draws
    it; two named, one line asking for --stage (never a silent pick of the first)."""
    import json
    from cs451.render import infer_stage
    from cs451.scene import BUNDLED_DIR, parse_scene
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    assert infer_stage(parse_scene(data)) == "radiosity"
    assert infer_stage(parse_scene({**data, "options": {}})) == "whitted"      # stage 1 draws no polygon
    both = tmp_path / "both.json"
    both.write_text(json.dumps({**data, "options": {"whitted": {}, "radiosity": {}}}))
    assert main(["render", str(both), "-o", str(tmp_path / "x.png")]) != 0
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "whitted, radiosity" in err and "--stage" in err, err
