"""No traceback from any input: scene files mutated at random, and command lines made of bad values.

Every outcome must be a drawn image or a one-line error naming the file (exit 2). The mutations are
seeded, so a failure here is reproducible by its case number; the work is bounded (small images, and
renders only for the stages that draw in well under a second).
"""
from __future__ import annotations

import copy
import json
import random
import re
from pathlib import Path

import pytest

from cs451.cli import main
from cs451.errors import KitError
from cs451.render import render_scene
from cs451.scene import BUNDLED_DIR, bundled_scenes, load_scene
from cs451.stages import get_stage, stage_names

VALUES = [None, True, False, 0, -1, 1, 2, 0.5, -0.0, 1e-300, 1e15, 1e16, 1e30, -1e308, 2**31, 2**64, float("nan"),
          float("inf"), "", "x", "sphere", [], [1], [1, 2], [0, 0, 0], [1e308, 0, 0], [[0, 0, 0]] * 3, {}, {"type": "x"},
          {"type": "sphere", "radius": 1}, {"type": "point", "position": [0, 0, 0]}]
CASES = 300
RENDERED_STAGES = ("sphere", "whitted")


def paths(data, prefix=()):
    """Every place in a JSON tree: (path, value)."""
    yield prefix, data
    if isinstance(data, dict):
        for k, v in data.items():
            yield from paths(v, prefix + (k,))
    elif isinstance(data, list):
        for i, v in enumerate(data):
            yield from paths(v, prefix + (i,))


def mutate(data: dict, rng: random.Random) -> dict:
    data = copy.deepcopy(data)
    places = [p for p, _ in paths(data) if p]
    for _ in range(rng.choice((1, 1, 2, 3))):
        path = rng.choice(places)
        key, action = path[-1], rng.random()
        try:
            parent = data
            for step in path[:-1]:   # an earlier mutation may have replaced a step with a number or a string
                parent = parent[step]
            if action < 0.15 and isinstance(parent, dict):
                del parent[key]
            elif action < 0.25 and isinstance(parent, dict):
                parent[f"unknown_{rng.randint(0, 9)}"] = rng.choice(VALUES)
            elif action < 0.35 and isinstance(parent[key], (int, float)) and not isinstance(parent[key], bool):
                parent[key] = parent[key] * rng.choice((-1, 0, 1e6, 1e-6, 1e12))
            else:
                parent[key] = copy.deepcopy(rng.choice(VALUES))
        except (KeyError, IndexError, TypeError):
            continue
    return data


def one_line(err: KitError, name: str) -> None:
    text = str(err)
    assert "\n" not in text and name in text, text


@pytest.fixture(scope="module")
def originals():
    return {n: json.loads((BUNDLED_DIR / f"{n}.json").read_text()) for n in bundled_scenes()}


@pytest.mark.filterwarnings("error::RuntimeWarning")   # an overflow is a silently wrong image
def test_mutated_scenes_are_drawn_or_refused_in_one_line(originals, tmp_path):
    rng = random.Random(451)
    refused = drawn = 0
    names = sorted(originals)
    for case in range(CASES):
        name = names[case % len(names)]
        path = tmp_path / f"case{case}-{name}.json"
        path.write_text(json.dumps(mutate(originals[name], rng)))
        try:
            scene = load_scene(path)
            for stage in stage_names():
                st = get_stage(stage)
                try:
                    st.check_scene(scene)
                    st.check_cost(scene, (16, 12))
                    st.options(scene)
                except KitError as err:
                    one_line(err, path.name)
        except KitError as err:
            one_line(err, path.name)
            refused += 1
            continue
        stage = next((s for s in scene.options if s in RENDERED_STAGES), None)
        if stage is None:
            continue
        try:
            render_scene(scene=str(path), output=tmp_path / "out.png", stage=stage, size="16x12")
            drawn += 1
        except KitError as err:
            one_line(err, path.name)
    assert refused > CASES // 4 and drawn > 10, (refused, drawn)   # the mutations reach both outcomes


BAD = ["", "-5x10", "0x0", "99999x99999", "1e30", "x", "/nonexistent/scene.json", "/etc", "/dev/null", "nosuch",
       "sphere", "whitted", "8x6", "out/", "a.jpg", "/etc/passwd/x.png", "S1,S99", "-1"]
OPTIONS = {"render": ["--impl", "--size", "--stage", "--shading", "-o"], "grade": ["--submission", "--tasks", "--jobs"],
           "scenes": [], "release": ["-o"]}


@pytest.mark.spawns
def test_bad_command_lines_end_in_one_line_and_exit_2(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    rng = random.Random(7)
    for case in range(120):
        command = rng.choice(sorted(OPTIONS))
        argv = [command] + ([rng.choice(["sphere", "whitted", "nosuch", "/dev/null", ""])] if command != "scenes" else [])
        for option in rng.sample(OPTIONS[command], k=min(len(OPTIONS[command]), rng.randint(0, 3))):
            argv += [option, rng.choice(BAD)]
        if command == "render" and "--size" not in argv:
            argv += ["--size", "8x6"]
        if command == "grade" and "--submission" not in argv:
            argv += ["--submission", "/nonexistent"]
        if command == "release" and "-o" not in argv:
            argv += ["-o", "/etc"]
        try:
            code = main(argv)
        except SystemExit as exit_:
            code = exit_.code
        err = capsys.readouterr().err
        assert code in (0, 2), (case, argv, code, err[-500:])
        assert "Traceback" not in err and "internal error" not in err, (case, argv, err[-500:])
        if code == 2:   # one line, after argparse's usage where the command line itself is wrong
            last = err.strip().splitlines()[-1] if err.strip() else ""
            assert last.startswith("cs451") and "error:" in last, (case, argv, err)
            assert err.count("error:") == 1, (case, argv, err)


def test_an_internal_error_is_one_line_with_a_way_to_the_traceback(capsys, monkeypatch):
    import cs451.render
    monkeypatch.setattr(cs451.render, "load_scene", lambda *_: 1 / 0)
    assert main(["render", "sphere", "-o", "x.png"]) == 3
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "ZeroDivisionError" in err and "CS451_TRACEBACK=1" in err


def _typo(word: str, rng: random.Random) -> str:
    """One edit: two letters swapped, or one dropped, doubled or changed."""
    k = rng.randrange(len(word) - 1)
    edits = (word[:k] + word[k + 1] + word[k] + word[k + 2:], word[:k] + word[k + 1:], word[:k] + word[k] * 2 + word[k:],
             word[:k] + rng.choice("aeiouxz") + word[k + 1:])
    return rng.choice([e for e in edits if e != word] or [word + "x"])


def _hostile(name: str, data: dict, rng: random.Random) -> tuple[str, str]:
    """A scene's text with one mistake of a class the issue-38 corpus found, and what the refusal must say."""
    d = copy.deepcopy(data)
    kind = rng.choice(("duplicate", "typo", "concave", "zero-area", "tiny-vector", "non-finite"))
    objects = [o for o in d["objects"] if o.get("type") in ("sphere", "polygon", "plane")]
    if kind == "typo":
        record = rng.choice([d["camera"], d["image"]] + objects)
        key = rng.choice([k for k in record if k != "type" and len(k) > 3])
        wrong = _typo(key, rng)
        if wrong in record:
            return json.dumps(d), ""
        record[wrong] = record.pop(key)
        return json.dumps(d), f"{wrong}: unknown field"
    if kind == "concave":
        s = rng.uniform(0.05, 0.45)     # the third corner pulled inside the square: a reflex corner
        d["objects"].append({"type": "polygon", "vertices": [[0, 0, 0], [2, 0, 0], [s, 0, s], [0, 0, 2]]})
        return json.dumps(d), "not convex"
    if kind == "zero-area":
        u, k = [rng.uniform(-1, 1) for _ in range(3)], rng.choice((2, -0.5, 3))
        d["lights"].append({"type": "area", "corner": [0, 1, 0], "edge_u": u, "edge_v": [k * c for c in u],
                            "radiance": [1, 1, 1]})
        return json.dumps(d), "no area"
    if kind == "tiny-vector":
        tiny = [0.0, 10.0 ** -rng.randint(31, 320), 0.0]
        d["camera"]["up"] = tiny
        return json.dumps(d), "too short to give a direction"
    if kind == "non-finite":
        d["camera"]["fovy"] = 30.0
        value = rng.choice(("NaN", "Infinity", "-Infinity", "1e400", "-1e999"))
        text = re.sub(r'"fovy": [^,}]+', f'"fovy": {value}', json.dumps(d))
        return text, "not allowed in a scene file" if value[-1].isalpha() else "camera.fovy: must be a finite number"
    text = json.dumps(d)                # duplicate: a key of the camera given again
    return text.replace('"camera": {', '"camera": {"eye": [9, 9, 9], ', 1), "camera.eye: appears twice"


HOSTILE_CASES = 240


def test_hostile_classes_are_refused_in_one_line_naming_what_is_wrong(originals, tmp_path):
    """Issue 38's classes, with random parameters: every one refused in one line naming the file, and saying
    what is wrong; misspelt keys each with a suggestion of the key meant."""
    rng = random.Random(38)
    outcomes: dict[str, int] = {}
    names = sorted(originals)
    for case in range(HOSTILE_CASES):
        name = names[case % len(names)]
        text, expected = _hostile(name, originals[name], rng)
        if not expected:
            continue
        path = tmp_path / f"hostile{case}.json"
        path.write_text(text)
        with pytest.raises(KitError) as err:
            load_scene(path)
        one_line(err.value, path.name)
        assert expected in str(err.value), (case, str(err.value))
        if "unknown field" in expected:
            assert "did you mean" in str(err.value), str(err.value)
        outcomes[expected.split(":")[-1].strip()] = outcomes.get(expected.split(":")[-1].strip(), 0) + 1
    print(f"\n{sum(outcomes.values())} hostile scenes, all refused in one line: {outcomes}")
    assert len(outcomes) >= 6 and sum(outcomes.values()) > HOSTILE_CASES * 0.8, outcomes
