"""Stage 4's direct surface reflection (notes §2.3): the Phong highlight the display adds to the Gouraud colours.

Truths: where the highlight peaks (the mirror image of the light's centre about the glossy floor, projected into
the camera), its radiance for a small light (k_s (n+2)/(2π) cos^n α · L·A · cos θ_x cos θ_y / r², the normalised
Phong lobe of :mod:`cs451.stages.radiosity.highlight`), a large light against a fine numerical integral over its area, and
bit-for-bit the old image wherever there is nothing to add (no glossy material, the option off, a light facing
away). Each scene is a floor of one patch under one light, so the diffuse part is flat and the highlight is the
difference between two drawings of the same solve.
"""
from __future__ import annotations

import json
import math

import numpy as np
import pytest

from cs451 import KIT_ROOT
from cs451.stages.radiosity import highlight as G
from cs451.stages.radiosity.display import GouraudDrawer, camera_matrix
from cs451.errors import KitError
from cs451.impl import load_impl, resolve_impl
from cs451.scene import BUNDLED_DIR, load_scene, parse_scene
from cs451.stages import get_stage
from cs451.stages import radiosity as R

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
SIZE = (160, 120)
EYE = (0.43, 1.2, 2.2)
UP = np.array([0.0, 1.0, 0.0])
#: the light's centre: off the vertical plane through the eye and the point looked at, so that its mirror image
#: projects off the image's centre column
LIGHT = (0.25, 1.0, -0.15)


def floor_scene(side: float = 0.02, radiance=(1000.0, 500.0, 2000.0), specular=(0.4, 0.2, 0.1), shininess=500.0,
                facing: float = -1.0, eye=EYE) -> dict:
    """A 4 × 4 glossy floor (y = 0, facing up, one patch) under a square light of this side centred at ``LIGHT``.

    ``facing`` −1: the light shines down (edge_u × edge_v = −y), +1: up, away from the floor.
    """
    s = side
    u, v = ([s, 0, 0], [0, 0, s]) if facing < 0 else ([0, 0, s], [s, 0, 0])
    return {
        "image": {"width": SIZE[0], "height": SIZE[1]},
        "camera": {"eye": list(eye), "center": [0, 0, 0], "fovy": 50, "near": 0.05, "far": 20},
        "lights": [{"type": "area", "corner": [LIGHT[0] - s / 2, LIGHT[1], LIGHT[2] - s / 2], "edge_u": u, "edge_v": v,
                    "radiance": list(radiance)}],
        "materials": {"floor": {"diffuse": [0.5, 0.5, 0.5], "specular": list(specular), "shininess": shininess}},
        "objects": [{"type": "polygon", "vertices": [[-2, 0, 2], [2, 0, 2], [2, 0, -2], [-2, 0, -2]],
                     "material": "floor"}],
        "options": {"radiosity": {}},
    }


def scene_file(tmp_path, data: dict):
    """``data`` loaded from a file ``floor.json``, as ``cs451 render`` loads it (errors name the file)."""
    path = tmp_path / "floor.json"
    path.write_text(json.dumps(data))
    return load_scene(path)


def drawn(data: dict, **overrides) -> tuple[np.ndarray, np.ndarray, object]:
    """One solve drawn twice, with and without the highlight: (with, without, scene)."""
    scene = parse_scene(data, "floor.json")
    opts = R.STAGE.options(scene, **overrides)
    patches = R.make_patches(scene, REF, opts.patch_size)
    sol = R.solve(patches, REF, opts)
    shine = G.highlight(scene, patches, opts.specular_samples)
    drawer = GouraudDrawer()
    plain = R.draw_solution(scene, REF, patches, sol.display, None, drawer=drawer)
    glossy = R.draw_solution(scene, REF, patches, sol.display, None, drawer=drawer, highlight=shine)
    return glossy, plain, scene


def brightest(highlight: np.ndarray) -> tuple[int, int]:
    r, c = np.unravel_index(np.argmax(highlight.sum(axis=2)), highlight.shape[:2])
    return int(r), int(c)


def project(scene, point) -> tuple[float, float]:
    """A world point's (row, column) in pixels, pixel centres at integers, row 0 at the top (as images are)."""
    w, h = scene.image.width, scene.image.height
    q = camera_matrix(scene, w, h, R.camera_view(scene)) @ np.append(point, 1.0)
    q = q[:3] / q[3]
    return (1 - q[1]) / 2 * h - 0.5, (q[0] + 1) / 2 * w - 0.5


def floor_point(scene, row: int, col: int) -> np.ndarray:
    """Where the ray through a pixel's centre meets the floor y = 0."""
    w, h = scene.image.width, scene.image.height
    inv = np.linalg.inv(camera_matrix(scene, w, h, R.camera_view(scene)))
    x, y = (col + 0.5) / w * 2 - 1, 1 - (row + 0.5) / h * 2
    a, b = (inv @ [x, y, z, 1.0] for z in (-1.0, 1.0))
    a, b = a[:3] / a[3], b[:3] / b[3]
    return a + a[1] / (a[1] - b[1]) * (b - a)


def mirror_point(eye, light) -> np.ndarray:
    """Where the floor y = 0 mirrors ``light`` into ``eye``: the line from the eye to the light's mirror image."""
    eye, image = np.asarray(eye, float), np.asarray(light, float) * [1, -1, 1]
    return eye + eye[1] / (eye[1] - image[1]) * (image - eye)


def small_light(point, light, power, specular, n, eye=EYE) -> np.ndarray:
    """The closed form for a light small against its distance: one point of radiance × area ``power``."""
    d = np.asarray(light, float) - point
    r2 = d @ d
    wi, wo = d / math.sqrt(r2), (np.asarray(eye, float) - point) / np.linalg.norm(np.asarray(eye, float) - point)
    cos_x = cos_y = wi @ UP                                        # the light faces straight down
    cos_a = max((2 * cos_x * UP - wi) @ wo, 0.0)
    return np.asarray(specular) * (n + 2) / (2 * math.pi) * cos_a ** n * np.asarray(power) * cos_x * cos_y / r2


@pytest.mark.parametrize("eye", [EYE, (-0.9, 0.8, 1.6), (1.3, 2.0, 1.0)])
def test01_the_highlight_peaks_where_the_floor_mirrors_the_lights_centre(eye):
    glossy, plain, scene = drawn(floor_scene(eye=eye))
    r, c = brightest(glossy - plain)
    want = project(scene, mirror_point(eye, LIGHT))
    assert max(abs(r - want[0]), abs(c - want[1])) <= 1.0, ((r, c), want)


def test02_the_peak_radiance_is_the_small_light_closed_form_per_channel():
    data = floor_scene()
    glossy, plain, scene = drawn(data)
    highlight = glossy - plain
    r, c = brightest(highlight)
    power = np.asarray(data["lights"][0]["radiance"]) * 0.02 ** 2
    specular, n = data["materials"]["floor"]["specular"], data["materials"]["floor"]["shininess"]
    at_pixel = small_light(floor_point(scene, r, c), LIGHT, power, specular, n)
    np.testing.assert_allclose(highlight[r, c], at_pixel, rtol=0.01)
    at_mirror = small_light(mirror_point(EYE, LIGHT), LIGHT, power, specular, n)   # cos α = 1 there
    np.testing.assert_allclose(highlight[r, c], at_mirror, rtol=0.04)
    assert highlight[r, c, 0] > 2.5                                    # about 3: far above the flat floor's 1/π·B


def lobe_integral(point, side: float, L: float, ks: float, n: float, cells: int = 200) -> float:
    """The highlight of a square light of this side centred at ``LIGHT``, facing down: a fine midpoint rule."""
    t = (np.arange(cells) + 0.5) / cells * side - side / 2
    y = np.stack(np.meshgrid(t, t), axis=-1).reshape(-1, 2)
    d = np.column_stack([y[:, 0], np.zeros(len(y)), y[:, 1]]) + LIGHT - point
    r2 = (d * d).sum(axis=1)
    wi = d / np.sqrt(r2)[:, None]
    wo = (np.asarray(EYE) - point) / np.linalg.norm(np.asarray(EYE) - point)
    cos = wi[:, 1]                                                   # at the floor and at the light alike
    cos_a = np.maximum((2 * cos[:, None] * UP - wi) @ wo, 0.0)
    area = (side / cells) ** 2
    return float((ks * (n + 2) / (2 * math.pi) * cos_a ** n * L * area * cos * cos / r2).sum())


def test03_a_large_light_is_integrated_over_its_area():
    """A 0.6 × 0.6 light 1 above the floor, a broad lobe (n = 10): a 4 × 4 grid within 2% of a 200 × 200 integral."""
    side, n, L, ks = 0.6, 10.0, 100.0, 0.5
    data = floor_scene(side=side, radiance=(L, L, L), specular=(ks, ks, ks), shininess=n)
    glossy, plain, scene = drawn(data)
    coarse, _, _ = drawn(data, specular_samples=1)
    r0, c0 = brightest(glossy - plain)
    errors, coarse_errors = [], []
    for r, c in ((r0, c0), (r0 - 12, c0 + 9), (r0 + 10, c0 - 15)):
        exact = lobe_integral(floor_point(scene, r, c), side, L, ks, n)
        errors.append(abs((glossy - plain)[r, c, 0] - exact) / exact)
        coarse_errors.append(abs((coarse - plain)[r, c, 0] - exact) / exact)
    assert max(errors) < 0.02, errors
    assert max(coarse_errors) > 2 * max(errors), (coarse_errors, errors)   # the grid, not luck: one point is worse


def test04_no_glossy_material_draws_exactly_the_old_image():
    dull = floor_scene(specular=(0.0, 0.0, 0.0))
    on = R.render(parse_scene(dull, "dull.json"), REF, quiet=True)
    off = R.render(parse_scene(dull, "dull.json"), REF, quiet=True, specular=False)
    assert np.array_equal(on, off)
    for name in ("cornell-box", "furnace", "room"):                   # the bundled scenes are drawn as before
        scene = load_scene(name)
        assert G.highlight(scene, R.make_patches(scene, REF, 0.0)) is None, name
    # the glossy shader itself adds exactly nothing where k_s is 0
    scene = parse_scene(floor_scene(), "floor.json")
    patches = R.make_patches(scene, REF, 0.0)
    shine = G.highlight(scene, patches)
    zero = G.Highlight(shine.normals, np.zeros_like(shine.coefficients) + [0, 0, 0, 500], shine.lights, shine.eye)
    display = np.full((len(patches), 3), 0.7)
    a = R.draw_solution(scene, REF, patches, display, None)
    b = R.draw_solution(scene, REF, patches, display, None, highlight=zero)
    assert np.array_equal(a, b)


def test05_turning_the_option_off_removes_the_highlight():
    data = floor_scene()
    dull = floor_scene(specular=(0.0, 0.0, 0.0))
    on = R.render(parse_scene(data, "floor.json"), REF, quiet=True)
    off = R.render(parse_scene(data, "floor.json"), REF, quiet=True, specular=False)
    old = R.render(parse_scene(dull, "dull.json"), REF, quiet=True)
    assert np.array_equal(off, old)
    assert (on - off).max() > 1.0 and (on >= off).all()
    data["options"]["radiosity"]["specular"] = False                  # the same from the scene file
    assert np.array_equal(R.render(parse_scene(data, "floor.json"), REF, quiet=True), old)


@pytest.mark.parametrize("case", ["light facing away", "floor seen from below", "shininess 0"])
def test06_nothing_is_reflected_from_behind_a_surface_or_by_a_flat_lobe(case):
    data = {"light facing away": floor_scene(facing=1.0), "floor seen from below": floor_scene(eye=(0.43, -1.2, 2.2)),
            "shininess 0": floor_scene(shininess=0.0)}[case]
    glossy, plain, _ = drawn(data)
    assert np.array_equal(glossy, plain), np.abs(glossy - plain).max()


def test07_the_bundled_glossy_box_shows_its_highlight_where_the_floor_mirrors_the_light(tmp_path):
    from cs451.cli import main
    from cs451.imageio import load_png
    scene = load_scene("glossy-box")
    glossy, plain, _ = drawn(json.loads((BUNDLED_DIR / "glossy-box.json").read_text()))
    r, c = brightest(glossy - plain)
    light = scene.lights[0]
    centre = np.asarray(light.corner) + (np.asarray(light.edge_u) + np.asarray(light.edge_v)) / 2
    want = project(scene, mirror_point(scene.camera.eye, centre))
    assert max(abs(r - want[0]), abs(c - want[1])) <= 3.0, ((r, c), want)   # a 130 × 105 mm light: a broad blob
    assert (glossy - plain)[r, c, 0] > 10 * plain[r, c, 0]           # radiance: far above the floor's B/π there
    out = tmp_path / "glossy.png"
    assert main(["render", "glossy-box", "-o", str(out), "--size", "48x48"]) == 0
    image = load_png(out)
    assert image.shape == (48, 48, 3) and image.max() == 1.0            # the highlight saturates


@pytest.mark.parametrize("value,message", [(0, "between 1 and 16"), (17, "between 1 and 16"), ("4", "an integer"),
                                           (2.5, "an integer")])
def test08_bad_sample_counts_are_refused_in_one_line(value, message, tmp_path):
    data = floor_scene()
    data["options"]["radiosity"]["specular_samples"] = value
    with pytest.raises(KitError) as err:
        R.STAGE.options(scene_file(tmp_path, data))
    text = str(err.value)
    assert "\n" not in text and "floor.json" in text and "options.radiosity.specular_samples" in text, text
    assert message in text, text


def test09_too_many_light_samples_in_all_are_refused_before_solving(tmp_path):
    data = floor_scene()
    data["lights"] = data["lights"] * 5                               # 5 lights × 16² samples = 1280 > 1024
    data["options"]["radiosity"]["specular_samples"] = 16
    with pytest.raises(KitError) as err:
        R.render(scene_file(tmp_path, data), REF, quiet=True)
    text = str(err.value)
    assert "\n" not in text and "floor.json" in text and "options.radiosity.specular_samples" in text, text
    data["options"]["radiosity"]["specular"] = False                  # without the highlight, no limit
    R.render(scene_file(tmp_path, data), REF, (16, 12), quiet=True)


def test10_the_handout_shows_the_glossy_box_diagram_in_step_with_the_reference():
    import cs451.packaging.diagrams as D
    assert D.check_diagrams("radiosity") == [], "run `cs451 figures` to redraw it"
    handout = KIT_ROOT / "assignments" / get_stage("radiosity").handout / "README.md"
    assert "](diagrams/glossy-box.png)" in handout.read_text()
