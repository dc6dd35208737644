"""Scene files: bundled scenes load; bad input is refused with the file and JSON path, in one line."""
from __future__ import annotations

import json
import subprocess
import sys

import pytest

from cs451.errors import InputError, KitError
from cs451.scene import BUNDLED_DIR, Sphere, bundled_scenes, load_scene, parse_scene
from cs451.schema import describe
from cs451.scene import Material

GOOD = json.loads((BUNDLED_DIR / "sphere.json").read_text())


def bad(**changes):
    data = json.loads(json.dumps(GOOD))
    for path, value in changes.items():
        node = data
        keys = path.split("__")
        for k in keys[:-1]:
            node = node[int(k)] if k.isdigit() else node[k]
        last = keys[-1]
        if value is KeyError:
            del node[last]
        else:
            node[int(last) if last.isdigit() else last] = value
    return data


def test01_bundled_scenes_load():
    assert "sphere" in bundled_scenes()
    for name in bundled_scenes():
        scene = load_scene(name)
        assert scene.camera.far > scene.camera.near


def test02_sphere_scene_matches_the_original_program():
    s = load_scene("sphere")
    assert (s.camera.fovy, s.camera.near, s.camera.far, s.camera.eye) == (30, 2, 100, (0, 0, 8))
    light = s.lights[0]
    assert light.position == (10, 5, 20) and light.space == "world" and light.diffuse == (0.9, 0.9, 0.9)  # set after gluLookAt
    m = s.material("green")
    assert m.diffuse == (0.3, 0.9, 0.5) and m.shininess == 50 and m.ambient == (0.2, 0.2, 0.2)  # GL default ambient
    assert isinstance(s.objects[0], Sphere) and (s.objects[0].slices, s.objects[0].stacks) == (32, 32)


@pytest.mark.parametrize("changes, where, what", [
    ({"camera__eye": KeyError}, "camera.eye", "missing required field"),
    ({"camera__fovy": "thirty"}, "camera.fovy", "must be a number"),
    ({"objects__0__radius": -1}, "objects[0].radius", "must be > 0"),
    ({"objects__0__radius": 0}, "objects[0].radius", "must be > 0"),
    ({"objects__0__colour": [1, 0, 0]}, "objects[0].colour", "unknown field"),
    ({"objects__0__type": "torus"}, "objects[0].type", "unknown object type 'torus'"),
    ({"objects__0__material": "blue"}, "objects[0].material", "unknown material 'blue'"),
    ({"lights__0__diffuse": [1, 1]}, "lights[0].diffuse", "list of 3 numbers"),
    ({"lights__0__attenuation": [0, 0, 0]}, "lights[0].attenuation", "must not all be zero"),
    ({"camera__far": 1}, "camera.far", "greater than near"),
    ({"camera__up": [0, 0, 1]}, "camera.up", "parallel"),
    ({"materials__green__diffuse": [1.5, 0, 0]}, "materials.green.diffuse", "[0, 1]"),
    ({"image__width": 2.5}, "image.width", "must be an integer"),
])
def test03_bad_fields_are_named(changes, where, what):
    with pytest.raises(InputError) as err:
        parse_scene(bad(**changes), "box.json")
    assert err.value.file == "box.json" and err.value.path == where
    assert what in str(err.value) and "\n" not in str(err.value)


def test04_degenerate_polygon_is_refused():
    data = bad(objects=[{"type": "polygon", "vertices": [[0, 0, 0], [1, 0, 0], [2, 0, 0]]}])
    with pytest.raises(InputError, match=r"objects\[0\].vertices: degenerate polygon"):
        parse_scene(data, "poly.json")


def test05_nan_and_invalid_json_are_refused(tmp_path):
    nan = tmp_path / "nan.json"
    nan.write_text(json.dumps(GOOD).replace('"radius": 1', '"radius": NaN'))
    with pytest.raises(InputError, match="NaN is not allowed"):
        load_scene(nan)
    broken = tmp_path / "broken.json"
    broken.write_text("{\"camera\": ")
    with pytest.raises(InputError, match=r"broken.json: line 1 column \d+: invalid JSON"):
        load_scene(broken)
    with pytest.raises(KitError, match="unknown scene 'no-such-scene'"):
        load_scene("no-such-scene")


@pytest.mark.spawns
def test06_cli_prints_one_line_without_traceback(tmp_path):
    path = tmp_path / "bad.json"
    path.write_text(json.dumps(bad(objects__0__radius=-2)))
    proc = subprocess.run([sys.executable, "-m", "cs451.cli", "render", str(path), "-o", str(tmp_path / "x.png")],
                          capture_output=True, text=True)
    assert proc.returncode == 2
    assert proc.stderr.strip().count("\n") == 0 and "Traceback" not in proc.stderr
    assert "bad.json: objects[0].radius: must be > 0, got -2" in proc.stderr


def test07_fields_are_described_once_for_the_handout():
    text = describe(Material)
    assert "`diffuse`" in text and "default `(0.8, 0.8, 0.8)`" in text


def _nested(depth: int) -> str:
    """A scene file whose one sphere sits ``depth`` groups deep, written as text (json.dumps would recurse)."""
    inner = '{"type": "group", "objects": [' * depth + '{"type": "sphere", "radius": 1}' + "]}" * depth
    return '{"camera": {"eye": [0, 0, 8], "center": [0, 0, 0]}, "objects": [' + inner + "]}"


@pytest.mark.parametrize("depth, error", [(31, None), (32, "groups nest at most 31 deep"),
                                          (400, "nested too deeply"), (50_000, "nested too deeply")])
def test08_groups_nest_as_deep_as_the_modelview_stack_and_no_deeper(tmp_path, depth, error):
    path = tmp_path / f"nested-{depth}.json"
    path.write_text(_nested(depth))
    if error is None:
        assert load_scene(path).objects[0].objects[0].objects
        return
    with pytest.raises(InputError, match=error) as err:
        load_scene(path)
    assert str(path) in str(err.value) and "\n" not in str(err.value)


@pytest.mark.parametrize("transform, where, what", [
    ({"type": "scale", "factors": [1, 0, 1]}, "transform[0].factors", "no factor may be 0"),
    ({"type": "rotate", "angle": 30, "axis": [0, 0, 0]}, "transform[0].axis", "must not be the zero vector"),
    ({"type": "shear", "amount": 1}, "transform[0].type", "unknown transform type 'shear'"),
    ({"type": "translate"}, "transform[0].offset", "missing required field"),
])
def test09_bad_transforms_are_named(transform, where, what):
    data = {"camera": {"eye": [0, 0, 8], "center": [0, 0, 0]},
            "objects": [{"type": "group", "transform": [transform], "objects": [{"type": "sphere", "radius": 1}]}]}
    with pytest.raises(InputError, match=what) as err:
        parse_scene(data, "t.json")
    assert f"objects[0].{where}" in str(err.value)
