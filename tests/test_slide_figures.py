"""The slides' figures (cs451/slides/figures.py): each renders, is cached by what made it, and shows the truth.

Quick versions only (the tests' sizes); a module-wide cache folder, so a figure is drawn once however many
tests look at it. Truths are computed here, never read from the reference: eq. 7 and 8 of the notes for the
delta weights, closure for a closed box's row, the mirror formula and Snell's law for the ray tree.
"""
from __future__ import annotations

from pathlib import Path
from typing import Any

import numpy as np
import pytest
from PIL import Image

from cs451 import KIT_ROOT
from cs451.errors import KitError
from cs451.slides import canvas, figures, registry
from cs451.stages.whitted import figure_rays as whitted_rays
from cs451.stages import stage_names

QUICK = True


@pytest.fixture(scope="module")
def cache(tmp_path_factory: pytest.TempPathFactory) -> Path:
    return tmp_path_factory.mktemp("figures")


def pixels(path: Path) -> np.ndarray:
    with Image.open(path) as image:
        return np.asarray(image.convert("RGB")).astype(np.float64)


def reference_copy(make_submission: Any, name: str, edit: tuple[str, ...] = ()) -> Path:
    """Every stage of the kit's reference copied into one folder (conftest's ``make_submission``), with one
    replacement ``edit`` = (stage, file, old, new) in one file of it."""
    for stage in stage_names():
        root = make_submission(stage, *(edit[1:] if edit and edit[0] == stage else ()), name=name)
    return root


# --- eq. 7 and 8 of the notes, read back from the heat map's pixels ------------------------------------

def closed_form(table: str, resolution: int) -> np.ndarray:
    """ΔF at the cell centres (rows bottom to top): eq. 7 for the top face, eq. 8 for a side face."""
    h = 2.0 / resolution
    across = -1.0 + (np.arange(resolution) + 0.5) * h
    if table == "top":
        y, x = np.meshgrid(across, across, indexing="ij")
        return h * h / (np.pi * (x * x + y * y + 1.0) ** 2)
    z, y = np.meshgrid((np.arange(resolution // 2) + 0.5) * h, across, indexing="ij")
    return z * h * h / (np.pi * (y * y + z * z + 1.0) ** 2)


def heat_map_error(path: Path, table: str) -> float:
    """The largest difference, in units of the colour scale's top, between the value each cell's colour stands for
    (the nearest of viridis's 256 colours) and the closed form at that cell."""
    from matplotlib import colormaps
    facts = figures.figure_facts(path)
    r = facts["resolution"]
    x0, y0, x1, y1 = facts["regions"][table]
    truth = closed_form(table, r)
    rows = truth.shape[0]
    lut = colormaps[facts["cmap"]](np.linspace(0, 1, 256))[:, :3] * 255
    image = pixels(path)
    worst = 0.0
    for j in range(rows):
        for i in range(r):
            px = int(x0 + (i + 0.5) * (x1 - x0) / r)
            py = int(y1 - (j + 0.5) * (y1 - y0) / rows)          # row 0 is the bottom one
            k = int(np.argmin(np.square(lut - image[py, px]).sum(axis=1)))
            shown = facts["vmin"] + (k + 0.5) / 256 * (facts["vmax"] - facts["vmin"])
            worst = max(worst, abs(shown - truth[j, i]) / facts["vmax"])
    return worst


# --- tests ------------------------------------------------------------------------------------------------

@pytest.mark.parametrize("name", list(figures.FIGURES))
def test01_every_figure_renders_to_a_png_that_carries_its_key(cache: Path, name: str) -> None:
    path = figures.render_figure(name, cache, quick=QUICK)
    with Image.open(path) as image:
        image.verify()
    with Image.open(path) as image:
        assert image.format == "PNG"
        width, height = image.size
    assert 100 <= width <= 4000 and 80 <= height <= 4000, (width, height)
    assert pixels(path).std() > 5, "a blank picture"
    assert figures.figure_facts(path)["key"] == figures.figure_key(name, QUICK)
    description = figures.FIGURES[name]
    assert description and "\n" not in description


def test02_a_second_call_hits_the_cache(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    written = []
    write = figures._write_png
    monkeypatch.setattr(figures, "_write_png", lambda *args: written.append(args[0]) or write(*args))
    first = figures.render_figure("hemicube-delta-weights", tmp_path, quick=QUICK)
    stamp = first.stat().st_mtime_ns
    again = figures.render_figure("hemicube-delta-weights", tmp_path, quick=QUICK)
    assert again == first and again.stat().st_mtime_ns == stamp
    assert written == [first]
    assert figures.render_figure("hemicube-delta-weights", tmp_path) != first     # the full one is its own file


def test03_a_changed_reference_function_changes_the_key_and_the_figure(tmp_path: Path, make_submission: Any,
                                                                      monkeypatch: pytest.MonkeyPatch) -> None:
    """A deliberately wrong H1 (the top face's weights to the third power, not the second) in a copy of the
    reference: the figures drawn with stage 3 get new keys and the heat map stops following eq. 7; the others keep
    theirs."""
    cache = tmp_path / "cache"
    before = {name: figures.figure_key(name, QUICK) for name in figures.FIGURES}
    right = figures.render_figure("hemicube-delta-weights", cache, quick=QUICK)
    assert heat_map_error(right, "top") < 1 / 128
    right_pixels = pixels(right)
    monkeypatch.setattr(registry, "REFERENCE", reference_copy(make_submission, "same"))
    assert {name: figures.figure_key(name, QUICK) for name in figures.FIGURES} == before   # a copy is the same code
    monkeypatch.setattr(registry, "REFERENCE", reference_copy(make_submission, "wrong", (
        "hemicube", "tables.py", "top = area / (np.pi * (x * x + y * y + 1.0) ** 2)",
        "top = area / (np.pi * (x * x + y * y + 1.0) ** 3)")))
    after = {name: figures.figure_key(name, QUICK) for name in figures.FIGURES}
    changed = {name for name in figures.FIGURES if after[name] != before[name]}
    uses_h1 = {name for name, spec in registry.SPECS.items() if "hemicube" in spec.stages}
    assert changed == uses_h1
    assert {"hemicube-delta-weights", "hemicube-row", "whitted-ray-tree"} <= changed
    assert not changed & {"sphere-gouraud-vs-phong", "bench-whitted", "radiosity-progress"}
    wrong = figures.render_figure("hemicube-delta-weights", cache, quick=QUICK)
    assert wrong != right and not right.exists(), "the figure drawn again replaces the old one"
    assert pixels(wrong).shape == right_pixels.shape and np.abs(pixels(wrong) - right_pixels).max() > 50
    assert heat_map_error(wrong, "top") > 0.05
    assert list(cache.glob("hemicube-delta-weights-quick-*.png")) == [wrong]


def test04_a_changed_kit_module_changes_the_keys_of_the_figures_it_draws(tmp_path: Path,
                                                                        monkeypatch: pytest.MonkeyPatch) -> None:
    edited = tmp_path / "pictures.py"
    edited.write_text((KIT_ROOT / "cs451" / "formfactors" / "pictures.py").read_text() + "\n# changed\n")
    before = {name: figures.figure_key(name, QUICK) for name in ("hemicube-row", "hemicube-delta-weights")}
    module_file = figures._module_file
    monkeypatch.setattr(figures, "_module_file",
                        lambda name: edited if name == "cs451.formfactors.pictures" else module_file(name))
    assert figures.figure_key("hemicube-row", QUICK) != before["hemicube-row"]
    assert figures.figure_key("hemicube-delta-weights", QUICK) == before["hemicube-delta-weights"]


def test05_the_key_covers_the_reference_the_kit_and_this_module() -> None:
    labels = [label for label, _ in figures.figure_sources("hemicube-delta-weights")]
    assert "reference/hemicube/tables.py" in labels and "cs451.slides.figures" in labels
    assert "cs451.stages.hemicube" in labels
    labels = [label for label, _ in figures.figure_sources("radiosity-progress")]
    assert "reference/radiosity/shooting.py" in labels and "kit reference/hemicube/views.py" in labels
    assert figures.figure_key("hemicube-row", QUICK) != figures.figure_key("hemicube-row", False)


def test06_unknown_figures_are_refused_in_one_line_naming_the_known_ones(tmp_path: Path) -> None:
    with pytest.raises(KitError) as err:
        figures.render_figure("hemicube-veiws", tmp_path)
    message = str(err.value)
    assert "'hemicube-veiws'" in message and "hemicube-views" in message and "bench-radiosity" in message
    assert "\n" not in message
    assert not list(tmp_path.iterdir())


def test07_the_delta_weights_follow_eq_7_and_8_and_sum_to_one(cache: Path) -> None:
    path = figures.render_figure("hemicube-delta-weights", cache, quick=QUICK)
    facts = figures.figure_facts(path)
    r = facts["resolution"]
    top, side = closed_form("top", r), closed_form("side", r)
    assert facts["vmax"] == pytest.approx(top.max(), rel=1e-12)
    assert facts["sum"] == pytest.approx(top.sum() + 4 * side.sum(), rel=1e-12)
    assert abs(facts["sum"] - 1) < 0.6 / r ** 2                 # the midpoint rule's error, as the slide says
    assert heat_map_error(path, "top") < 1 / 128
    assert heat_map_error(path, "side") < 1 / 128


def test08_a_closed_box_row_sums_to_one(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("hemicube-row", cache, quick=QUICK))
    assert abs(facts["row_sum"] - 1) < 1e-3
    assert f"{facts['row_sum']:.4f}" in facts["caption"]
    assert facts["open_row_sum"] < 0.99                         # the open box loses what its front wall catches
    assert facts["open_row_sum"] + facts["front_wall"] == pytest.approx(facts["row_sum"], abs=1e-9)


def test09_the_ray_tree_obeys_the_mirror_law_and_snell(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("whitted-ray-tree", cache, quick=QUICK))
    assert np.abs(np.subtract(facts["first_hit_pixel"], facts["pixel"])).max() < 0.5   # W1 against the projection
    assert facts["rays"]["camera"] == 1 and facts["materials"][0] == "glass"
    assert min(facts["rays"][k] for k in ("reflection", "refraction", "shadow")) >= 1
    data = canvas.scene_data("whitted.json")
    rays = whitted_rays.ray_tree(data, [tuple(facts["pixel"])], (80, 60))
    camera = rays[0]
    d, n = camera["direction"], camera["normal"]
    assert d @ n < 0                                            # it enters the glass
    children = {r["kind"]: r for r in rays if r["parent"] == 0}
    assert np.allclose(children["reflection"]["direction"], d - 2 * (d @ n) * n, atol=1e-9)
    t = children["refraction"]["direction"]
    sin_i, sin_t = np.linalg.norm(np.cross(d, n)), np.linalg.norm(np.cross(t, n))
    assert sin_t == pytest.approx(sin_i / 1.5, rel=1e-9)        # the glass's index of refraction
    assert all(0 <= r["parent"] < len(rays) for r in rays[1:])
    assert {r["kind"] for r in rays} == {"camera", "reflection", "refraction", "shadow"}


def test10_the_ray_kinds_show_lit_dimmed_and_blocked_shadow_rays(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("whitted-ray-kinds", cache, quick=QUICK))
    assert facts["shadow"]["styles"] == ["blocked", "dimmed", "lit"]
    assert facts["reflection"]["rays"] >= 1 and facts["refraction"]["rays"] >= 1
    counters = facts["image_counters"]
    assert counters["camera"] == 80 * 60 and counters["shadow"] > 0


def test11_the_cutoff_trades_rays_for_error(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("whitted-cutoff", cache, quick=QUICK))
    cutoffs = sorted(facts["cut-off"], key=lambda r: -r["value"])          # 0.5 down to 0.001
    secondary = [r["reflection"] + r["transmission"] for r in cutoffs]
    assert secondary == sorted(secondary) and secondary[0] < secondary[-1]
    assert [r["error"] for r in cutoffs] == sorted((r["error"] for r in cutoffs), reverse=True)
    flat = next(r for r in facts["depth"] if r["value"] == 0)
    assert flat["reflection"] == flat["transmission"] == 0


def test12_the_hierarchy_holds_the_torus_and_spares_most_tests(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("whitted-hierarchy", cache, quick=QUICK))
    assert facts["primitives"] == 55_296 + 1                   # the torus's triangles and the mirror sphere
    assert facts["leaves"] == (facts["nodes"] + 1) // 2          # a binary tree
    assert facts["per_camera_ray"]["tests"] < facts["primitives"] / 100


def test13_progressive_refinement_shoots_the_light_down(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("radiosity-progress", cache, quick=QUICK))
    shots = sorted(facts["shots"], key=int)
    unshot = [facts["shots"][k]["unshot"] for k in shots]
    assert unshot == sorted(unshot, reverse=True) and 0 < unshot[-1] < 1


def test14_gouraud_differs_most_on_the_coarse_sphere(cache: Path) -> None:
    facts = figures.figure_facts(figures.render_figure("sphere-gouraud-vs-phong", cache, quick=QUICK))
    assert facts["12x8"]["mean_difference"] > facts["32x32"]["mean_difference"]
