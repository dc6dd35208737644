"""Stage 5: the path tracer agrees with radiosity, and the statistical tests tell right from wrong.

A statistical test is only worth its false alarms if it catches the mistakes students make: each mutant below is the
reference with one such mistake planted (a forgotten 1/p, the light counted twice, no bounce after the first, a
cosine dropped, uniform instead of cosine sampling), and each must fail the test that guards it, while the
reference passes under fresh random numbers.
"""
from __future__ import annotations

import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.grading.spec import Verdict
from cs451.impl import load_impl, resolve_impl
from cs451.stages import get_stage

sys.path.insert(0, str(KIT_ROOT))
from autograder.pathtrace import checks, public, truth  # noqa: E402

STAGE = get_stage("pathtrace")
REF = load_impl(resolve_impl("reference", "pathtrace"), "pathtrace")

#: (file, the reference's line, the mistake): each a way a student's tracer goes wrong
MUTANTS = {
    "roulette without 1/p": ("roulette.py", "out[alive] = beta[alive] / p[alive, None]", "out[alive] = beta[alive]"),
    "the light counted twice": ("tracer.py", "go = (tri >= 0) & ~scene.emitter[np.maximum(tri, 0)]",
                                "colour[path[(tri >= 0) & scene.emitter[np.maximum(tri, 0)] & (d @ scene.light_normal < 0)]]"
                                " += beta[(tri >= 0) & scene.emitter[np.maximum(tri, 0)] & (d @ scene.light_normal < 0)]"
                                " * scene.light_radiance\n        go = (tri >= 0) & ~scene.emitter[np.maximum(tri, 0)]"),
    "no bounce after the first": ("tracer.py", "for depth in range(scene.max_depth):", "for depth in range(1):"),
    "the light's cosine dropped": ("light.py", "geometry = cos_x[lit] * cos_l[lit] / r2[lit]", "geometry = cos_x[lit] / r2[lit]"),
}


def mutant(tmp_path: Path, name: str):
    file, line, wrong = MUTANTS[name]
    folder = tmp_path / name.replace(" ", "-").replace("/", "")
    shutil.copytree(resolve_impl("reference", "pathtrace"), folder, ignore=shutil.ignore_patterns("__pycache__"))
    text = (folder / file).read_text()
    assert line in text, f"the reference no longer has {line!r}: update the mutant"
    (folder / file).write_text(text.replace(line, wrong))
    return load_impl(folder, "pathtrace")


def radiosity_verdict(impl, seed: int) -> Verdict:
    test = next(t for t in public.TESTS if t.check.name == "like_radiosity")
    params = {**test.params, "seed": seed}
    out = STAGE.probes["polygon_radiance"](impl, **params)
    return checks.like_radiosity(out, truth.radiosity_radiance(params), params)


def test01_the_reference_is_radiosity_under_fresh_random_numbers():
    for seed in (11, 12, 13):
        verdict = radiosity_verdict(REF, seed)
        assert verdict.passed, verdict.message


@pytest.mark.parametrize("name", sorted(MUTANTS))
def test02_each_planted_mistake_fails_the_comparison_with_radiosity(name, tmp_path):
    verdict = radiosity_verdict(mutant(tmp_path, name), 11)
    assert not verdict.passed, f"{name}: {verdict.message}"


def test03_uniform_hemisphere_sampling_fails_the_cosine_test_and_malleys_passes():
    test = next(t for t in public.TESTS if t.check.name == "cosine_distributed")
    n = np.repeat(np.asarray(test.params["normals"], float), test.params["samples"], axis=0)
    rng = np.random.default_rng(3)
    d = rng.normal(size=n.shape)
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    d = np.where((np.einsum("ij,ij->i", d, n) < 0)[:, None], -d, d)       # uniform over the hemisphere
    assert not checks.cosine_distributed({"directions": d}, {}, test.params).passed
    good = STAGE.probes["cosine_sample"](REF, **{k: v for k, v in test.params.items()})
    assert checks.cosine_distributed(good, {}, test.params).passed


def test04_the_direct_light_mean_is_lamberts_formula():
    test = next(t for t in public.TESTS if t.check.name == "mean_matches")
    out = STAGE.probes["direct_light"](REF, **test.params)
    want = truth.lambert_irradiance(test.params)["radiance"]
    got = out["radiance"].reshape(len(want), test.params["samples"], 3).mean(axis=1)
    assert np.allclose(got, want, rtol=0.02), (got, want)          # 20,000 samples: about 0.5% of noise


@pytest.mark.spawns
def test05_the_bench_writes_its_table_and_plot_and_the_noise_falls_with_samples(bench_run):
    folder, done = bench_run("pathtrace")                  # the session's one run of cs451 bench pathtrace --quick
    assert done.returncode == 0, done.stderr[-2000:]
    import json
    result = json.loads((folder / "pathtrace.json").read_text())
    traced = [r for r in result["rows"] if r["method"] == "path tracing"]
    assert (folder / "pathtrace.png").is_file() and len(traced) == 2
    assert traced[1]["pixel_error"] < 0.75 * traced[0]["pixel_error"], traced     # 4x the samples: about half the noise


@pytest.mark.spawns
def test06_a_scene_this_stage_cannot_light_is_refused_in_one_line(tmp_path):
    import json
    from cs451.scene import BUNDLED_DIR
    data = json.loads((BUNDLED_DIR / "cornell-box.json").read_text())
    data["lights"] = data["lights"] * 2
    path = tmp_path / "two-lights.json"
    path.write_text(json.dumps(data))
    done = subprocess.run([str(Path(sys.executable).parent / "cs451"), "render", str(path), "--stage", "pathtrace",
                           "-o", str(tmp_path / "x.png")], capture_output=True, text=True, cwd=KIT_ROOT)
    assert done.returncode != 0 and len(done.stderr.strip().splitlines()) == 1 and "one area light" in done.stderr
