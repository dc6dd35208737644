"""Every kind of scene object and light, through every stage: drawn, or refused with one line naming it.

A kind the schema knows but a stage does not draw used to be skipped in silence (a spot light left a
scene dark). Each stage now declares what it draws (``Stage.draws``), ``cs451 render`` checks a scene
against it, and every consumer in the engine ends in an error rather than a skip. The spot light here is
added to the schema alone, as the next engineer would add one, and no stage has heard of it.
"""
from __future__ import annotations

import json
from dataclasses import dataclass

import pytest

from cs451 import schema
from cs451.errors import KitError
from cs451.impl import load_impl, resolve_impl
from cs451.render import render_scene
from cs451.scene import BUNDLED_DIR, Light, Object, bundled_scenes, load_scene, parse_scene
from cs451.schema import field
from cs451.stages import get_stage, stage_names

SIZE = "24x18"


@pytest.fixture
def spot_light():
    """A spot light added to the schema (and taken out again): a kind no stage draws yet."""
    @Light.register("spot")
    @dataclass(frozen=True)
    class SpotLight(Light):
        position: schema.Vec3 = field("Position.")
        direction: schema.Vec3 = field("Axis of the cone.", check=schema.nonzero_vector)
        cutoff: float = field("Half-angle of the cone in degrees.", 30.0, schema.positive)
        diffuse: schema.Vec3 = field("Colour.", (1.0, 1.0, 1.0), schema.non_negative)

    yield SpotLight
    del Light._registry["spot"]


#: one item of each kind, placed where it is seen by the base scenes below
ITEMS = {
    "sphere": {"type": "sphere", "radius": 0.3, "center": [0.6, 0.2, 0.4], "slices": 8, "stacks": 6},
    "plane": {"type": "plane", "point": [0, -1.5, 0], "normal": [0, 1, 0]},
    "polygon": {"type": "polygon", "vertices": [[-0.5, -0.5, 0.5], [0.5, -0.5, 0.5], [0.0, 0.5, 0.5]]},
    "mesh": {"type": "mesh", "file": str(BUNDLED_DIR / "rippled-torus.obj"), "scale": 0.2},
    "point": {"type": "point", "position": [2, 3, 4]},
    "directional": {"type": "directional", "direction": [0, -1, -1]},
    "area": {"type": "area", "corner": [-0.3, 1.4, -0.3], "edge_u": [0.6, 0, 0], "edge_v": [0, 0, 0.6],
             "radiance": [4, 4, 4], "samples": 2},
    "spot": {"type": "spot", "position": [0, 3, 3], "direction": [0, -1, -1]},
    "group": {"type": "group", "transform": [{"type": "translate", "offset": [-0.5, 0, 0.4]},
                                             {"type": "scale", "factors": [0.3, 0.2, 0.3]}],
              "objects": [{"type": "sphere", "radius": 1, "slices": 8, "stacks": 6}]},
}

#: two facing walls lit by an area light: the smallest scene stages 3 and 4 draw
PATCHES = {
    "image": {"width": 24, "height": 18},
    "camera": {"eye": [0, 0, 4], "center": [0, 0, 0], "up": [0, 1, 0], "fovy": 50},
    "materials": {"default": {"diffuse": [0.5, 0.5, 0.5]}},
    "objects": [{"type": "polygon", "vertices": [[-1, -1, -1], [1, -1, -1], [1, 1, -1], [-1, 1, -1]]},
                {"type": "polygon", "vertices": [[-1, -1.5, 1], [-1, -1.5, -1], [1, -1.5, -1], [1, -1.5, 1]]}],
    "lights": [ITEMS["area"]],
}


def base_scene(stage: str) -> dict:
    """The bundled scene named after the stage (its first object only), else the two walls and a light."""
    path = BUNDLED_DIR / f"{stage}.json"
    if path.exists():
        data = json.loads(path.read_text())
        data["objects"] = data["objects"][:1]
    else:
        data = json.loads(json.dumps(PATCHES))
    data.setdefault("materials", {}).setdefault("default", {"diffuse": [0.5, 0.5, 0.5]})
    data["options"] = {stage: data.get("options", {}).get(stage, {})}
    return data


def with_item(stage: str, kind: str) -> dict:
    data = base_scene(stage)
    group = "lights" if kind in Light._registry else "objects"
    kept = [item for item in data.get(group, []) if not (kind == "area" and item.get("type") == "area")]
    data[group] = kept + [ITEMS[kind]]        # the area light replaces the base's: stage 5 samples exactly one
    return data


def kind_class(kind: str) -> type:
    return Light._registry.get(kind) or Object._registry[kind]


def all_kinds() -> list[str]:
    return sorted(Light._registry) + sorted(Object._registry)


def test_every_registered_kind_has_an_item_here():
    """A kind added to the schema must be added to this test too (else it would pass unchecked)."""
    assert set(all_kinds()) <= set(ITEMS), f"no test item for {sorted(set(all_kinds()) - set(ITEMS))}"


@pytest.mark.parametrize("stage", stage_names())
def test_each_kind_is_drawn_or_refused_by_render(stage, spot_light, tmp_path):
    st = get_stage(stage)
    for kind in all_kinds():
        path = tmp_path / f"{stage}-{kind}.json"
        path.write_text(json.dumps(with_item(stage, kind)))
        drawn = issubclass(kind_class(kind), st.draws)
        try:
            out, _ = render_scene(scene=str(path), output=tmp_path / f"{stage}-{kind}.png", stage=stage, size=SIZE)
        except KitError as err:
            message = str(err)
            if drawn:
                raise
            assert "\n" not in message
            assert path.name in message, message
            assert f"stage {st.number}" in message, message
            assert f"draw a {kind}" in message, message
            continue
        assert not drawn or out.exists(), f"{stage} draws {kind} but wrote nothing"
        assert drawn, f"stage {stage} does not declare {kind} and yet drew it"


@pytest.mark.parametrize("stage", stage_names())
def test_the_engine_alone_refuses_what_it_does_not_draw(stage, spot_light):
    """Past the stage's check (a caller that forgot it), each consumer still ends in an error naming the kind."""
    st = get_stage(stage)
    ref = load_impl(resolve_impl("reference", stage), stage)
    for kind in all_kinds():
        cls = kind_class(kind)
        if issubclass(cls, st.draws):
            continue
        scene = parse_scene(with_item(stage, kind), f"{stage}-{kind}.json")
        with pytest.raises(KitError) as err:
            st.render(scene, ref, (24, 18))
        assert cls.__name__ in str(err.value) and "\n" not in str(err.value), str(err.value)


def test_the_spot_light_is_refused_from_the_command_line(spot_light, tmp_path, capsys):
    from cs451.cli import main
    path = tmp_path / "spot.json"
    path.write_text(json.dumps(with_item("whitted", "spot")))
    assert main(["render", str(path), "--stage", "whitted", "-o", str(tmp_path / "out.png")]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "lights[" in err[0] and "spot light" in err[0] and "stage 2" in err[0], err


@pytest.mark.parametrize("name", bundled_scenes())
def test_every_bundled_scene_is_drawn_by_its_stage_and_refused_or_drawn_by_the_rest(name):
    scene = load_scene(name)
    own = [s for s in scene.options if s in stage_names()]
    for stage in stage_names():
        st = get_stage(stage)
        try:
            st.check_scene(scene)
        except KitError as err:
            assert stage not in own, f"{name} is meant for {stage}, which refuses it: {err}"
            assert "\n" not in str(err) and f"stage {st.number}" in str(err)


def test_declared_kinds_are_scene_kinds():
    for stage in stage_names():
        for cls in get_stage(stage).draws:
            assert cls in Light._registry.values() or cls in Object._registry.values(), (stage, cls)
    assert all(get_stage(s).draws for s in stage_names()), "a stage that declares no kinds would refuse every scene"


def test_a_group_holding_what_stage_1_does_not_draw_is_refused_by_its_path(tmp_path):
    """A plane inside a group gets past the top-level check; the walk of the groups names it where it is."""
    data = with_item("sphere", "group")
    data["objects"][-1]["objects"].append(ITEMS["plane"])
    path = tmp_path / "plane-in-a-group.json"
    path.write_text(json.dumps(data))
    with pytest.raises(KitError, match=r"objects\[1\]\.objects\[1\]: stage 1 draws spheres, not a Plane"):
        render_scene(scene=str(path), output=tmp_path / "out.png", stage="sphere", size=SIZE)
