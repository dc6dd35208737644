"""A new corpus of user mistakes in scene files (issue 38): each refused in one line that names the file, the
field and the value, through the console script, with the process's peak memory measured.

Each case here was once accepted silently (a concave polygon drawn 44% too large, a duplicate key whose first
value vanished), blamed on the wrong thing (a tiny `up` on task W1, a zero-area light on "patch 892"), or
ran the machine out of memory or time (2³¹ light samples, a polygon of 2 million corners). Hostile files
(FIFOs, links to /dev/zero) are made here, in a temporary folder, and never copied.
"""
from __future__ import annotations

import json
import math
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from cs451.scene import BUNDLED_DIR, MAX_OBJECTS, MAX_SCENE_BYTES, load_scene
from cs451.errors import KitError

#: the most memory one refusal may take (the issue's bound)
PEAK_KB = 500_000
MEASURED = ("import resource, subprocess, sys\n"
            "p = subprocess.run(sys.argv[1:])\n"
            "print('peak', resource.getrusage(resource.RUSAGE_CHILDREN).ru_maxrss, file=sys.stderr)\n"
            "sys.exit(p.returncode)\n")


def console_script() -> list[str]:
    script = Path(sys.executable).with_name("cs451")
    return [str(script)] if script.exists() else [sys.executable, "-m", "cs451"]


def bundled(name: str) -> dict:
    return json.loads((BUNDLED_DIR / f"{name}.json").read_text())


def area_light(**extra) -> dict:
    return {"type": "area", "corner": [0, 5, 0], "edge_u": [1, 0, 0], "edge_v": [0, 0, 1], "radiance": [1, 1, 1],
            **extra}


def whitted(change) -> dict:
    d = bundled("whitted")
    change(d)
    return d


def ring(n: int) -> list:
    return [[math.cos(2 * math.pi * k / n), 0.01, math.sin(2 * math.pi * k / n)] for k in range(n)]


SCENES = {   # name: (the scene, the stage, what the one line must say after "file: ")
    "area-light-samples": (whitted(lambda d: d["lights"].append(area_light(samples=2**31 - 1))), None,
                           "lights[2].samples: must be at most 4,096"),
    "light-samples-option": (whitted(lambda d: (d["lights"].append(area_light()),
                                                d["options"]["whitted"].update(light_samples=10**6))), None,
                             "options.whitted.light_samples: must be at most 4,096"),
    "no-objects": (whitted(lambda d: d.update(objects=[])), "whitted", "objects: the scene has no objects"),
    "concave-polygon": (whitted(lambda d: d["objects"].append(
        {"type": "polygon", "vertices": [[0, 0.01, 0], [2, 0.01, 0], [0.2, 0.01, 0.2], [0, 0.01, 2]]})), None,
        "objects[3].vertices[2]: the polygon is not convex"),
    "repeated-corner": (whitted(lambda d: d["objects"].append(
        {"type": "polygon", "vertices": [[0, 0.01, 0], [1, 0.01, 0], [1, 0.01, 0], [0, 0.01, 1]]})), None,
        "objects[3].vertices[2]: repeats the corner before it"),
    "misspelt-option": (whitted(lambda d: d["options"].update(radiosity={"toleranse": 1e-4})), None,
                        "options.radiosity.toleranse: unknown field (did you mean 'tolerance'?)"),
    "misspelt-stage": (whitted(lambda d: d["options"].update(radiosty={})), None,
                       "options.radiosty: no stage is called 'radiosty' (did you mean 'radiosity'?)"),
    "misspelt-field": (whitted(lambda d: d["camera"].update(fvoy=30)), None,
                       "camera.fvoy: unknown field (did you mean 'fovy'?)"),
    "misspelt-kind": (whitted(lambda d: d["objects"][1].update(type="sphre")), None,
                      "objects[1].type: unknown object type 'sphre' (did you mean 'sphere'?)"),
    "tiny-up": (whitted(lambda d: d["camera"].update(up=[0, 1e-300, 0])), None,
                "camera.up: is too short to give a direction"),
    "tiny-view": (whitted(lambda d: d["camera"].update(eye=[0, 0, 0], center=[1e-300, 0, 0])), None,
                  "camera.center: must differ from eye"),
    "tiny-axis": ({**bundled("sphere"), "objects": [{"type": "group", "objects": bundled("sphere")["objects"],
                  "transform": [{"type": "rotate", "angle": 30, "axis": [0, 1e-300, 0]}]}]}, None,
                  "objects[0].transform[0].axis: is too short to give a direction"),
    "zero-area-light": (whitted(lambda d: d.update(lights=[area_light(edge_v=[2, 0, 0])])), None,
                        "lights[0].edge_v: is parallel to edge_u"),
    "too-many-objects": (whitted(lambda d: d.update(objects=[{"type": "sphere", "radius": 0.01}] * (MAX_OBJECTS + 1))),
                         "sphere", f"objects: {MAX_OBJECTS + 1:,} objects, over the {MAX_OBJECTS:,}"),
    "huge-polygon": (whitted(lambda d: d["objects"].append({"type": "polygon", "vertices": ring(20_000)})), None,
                     "objects[3].vertices: must hold at most 10,000 items"),
}


def write_special(tmp_path: Path, kind: str) -> tuple[Path, str]:
    """A scene path that is not a regular file, and what the message must call it."""
    path = tmp_path / f"{kind}.json"
    if kind == "fifo":
        os.mkfifo(path)
        return path, "a named pipe (FIFO), not a scene file"
    if kind == "dev-zero":
        path.symlink_to("/dev/zero")
        return path, "a character device (/dev/zero), not a scene file"
    if kind == "folder":
        path.mkdir()
        return path, "a folder, not a scene file"
    if kind == "dangling":
        path.symlink_to(tmp_path / "nowhere.json")
        return path, "a broken symbolic link, not a scene file"
    with open(path, "wb") as f:     # sparse: the size is real, the disk holds nothing
        f.truncate(MAX_SCENE_BYTES + 1)
    return path, "16.0 MB, over the 16 MB a scene file may be"


def run_measured(args: list[str], cwd: Path) -> tuple[int, str, int]:
    done = subprocess.run([sys.executable, "-c", MEASURED, *console_script(), *args], cwd=cwd, capture_output=True,
                          text=True, timeout=120)
    lines = done.stderr.strip().splitlines()
    return done.returncode, "\n".join(lines[:-1]), int(lines[-1].split()[1])


def assert_one_line(code: int, err: str, peak: int, expected: str) -> None:
    assert code == 2 and len(err.splitlines()) == 1, err
    assert expected in err and err.startswith("cs451: error:"), err
    assert "Traceback" not in err and "Warning" not in err, err
    assert peak < PEAK_KB, f"peak {peak} KB"


@pytest.mark.spawns
@pytest.mark.parametrize("case", sorted(SCENES))
def test_a_mistaken_scene_is_refused_in_one_line_naming_the_field(case, tmp_path):
    data, stage, expected = SCENES[case]
    path = tmp_path / f"{case}.json"
    path.write_text(json.dumps(data))
    code, err, peak = run_measured(["render", str(path), "-o", "out.png", "--size", "32x24"]
                                   + (["--stage", stage] if stage else []), tmp_path)
    assert_one_line(code, err, peak, f"{path}: {expected}")
    assert not (tmp_path / "out.png").exists()


@pytest.mark.spawns
@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "folder", "dangling", "oversized"])
def test_a_scene_path_that_is_no_scene_file_is_named_for_what_it_is(kind, tmp_path):
    path, expected = write_special(tmp_path, kind)
    code, err, peak = run_measured(["render", str(path), "-o", "out.png"], tmp_path)
    assert_one_line(code, err, peak, expected)


def test_a_duplicate_key_is_refused_at_its_path(tmp_path):
    text = json.dumps(bundled("whitted"))
    top = tmp_path / "top.json"
    top.write_text(text[:-1] + ', "name": "again"}')
    inner = tmp_path / "inner.json"
    inner.write_text(text.replace('"max_depth": 6', '"max_depth": 6, "max_depth": 2'))
    for path, field in ((top, "name"), (inner, "options.whitted.max_depth")):
        with pytest.raises(KitError, match=rf"{path.name}: {field}: appears twice"):
            load_scene(path)


OBJ = {   # the mesh file's text, and what the message must say
    "nan": ("v 0 0 0\nv 1 0 0\nv nan 1 0\nf 1 2 3\n", "nan.obj, line 3: vertex 3 is [nan, 1.0, 0.0]"),
    "huge": ("# a comment\nv 0 0 0\nv 1 0 0\nv 1e300 1 0\nf 1 2 3\n", "huge.obj, line 4: vertex 3 is [1e+300"),
    "junk": ("v 0 0 0\nv 1 0 0\nv 1 1 x\nf 1 2 3\n", "junk.obj, line 3: a vertex must be three numbers"),
    "missing-vertex": ("v 0 0 0\nv 1 0 0\nv 1 1 0\nf 1 2 9\n", "missing-vertex.obj, line 4: vertex 9 does not exist here"),
}


@pytest.mark.spawns
@pytest.mark.parametrize("name", sorted(OBJ))
def test_a_bad_obj_file_is_refused_with_its_line(name, tmp_path):
    text, expected = OBJ[name]
    (tmp_path / f"{name}.obj").write_text(text)
    scene = whitted(lambda d: d["objects"].append({"type": "mesh", "file": f"{name}.obj"}))
    (tmp_path / "s.json").write_text(json.dumps(scene))
    code, err, peak = run_measured(["render", "s.json", "-o", "out.png", "--size", "32x24"], tmp_path)
    assert_one_line(code, err, peak, f"s.json: objects[3].file: {expected}")


def test_a_render_past_the_time_budget_is_refused_before_it_starts(tmp_path, monkeypatch):
    from cs451.cli import main
    scene = whitted(lambda d: (d["lights"].append(area_light(samples=4096)), d["options"]["whitted"].update(spp=16)))
    (tmp_path / "slow.json").write_text(json.dumps(scene))
    monkeypatch.chdir(tmp_path)
    assert main(["render", "slow.json", "-o", "out.png", "--size", "1000x1000"]) == 2
    monkeypatch.setenv("CS451_TIME_BUDGET", "1e9")   # said on purpose: then only memory may refuse it
    from cs451.stages import get_stage
    get_stage("whitted").check_cost(load_scene(tmp_path / "slow.json"), (1000, 1000))


def test_the_exported_json_schema_is_in_step_and_agrees_with_the_loader():
    """docs/scene.schema.json is what the code declares; jsonschema (an independent validator) accepts every
    bundled scene with it and flags the typos the loader refuses."""
    jsonschema = pytest.importorskip("jsonschema")
    from cs451.scene_schema import SCHEMA_FILE, schema_text
    assert SCHEMA_FILE.read_text() == schema_text(), "run `cs451 scenes --schema > docs/scene.schema.json`"
    schema = json.loads(schema_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    check = jsonschema.Draft202012Validator(schema)
    for name in sorted(p.stem for p in BUNDLED_DIR.glob("*.json")):
        assert not list(check.iter_errors(bundled(name))), name
    for case in ("misspelt-option", "misspelt-field", "misspelt-kind", "area-light-samples", "light-samples-option"):
        assert list(check.iter_errors(SCENES[case][0])), case


def test_the_budget_follows_the_process_address_space_limit(monkeypatch):
    """The budget follows RLIMIT_AS where one is set (ulimit -v): the root cgroup says nothing of it."""
    import resource
    from cs451 import limits
    soft, hard = resource.getrlimit(resource.RLIMIT_AS)
    monkeypatch.setattr(resource, "getrlimit", lambda which: (6 * 2**30, hard) if which == resource.RLIMIT_AS
                        else (soft, hard))
    monkeypatch.delenv("CS451_MEMORY_BUDGET", raising=False)
    budget, why = min(limits.memory_limits())
    assert budget < 3 * 2**30 and "RLIMIT_AS" in why


def test_the_cgroup_limit_is_the_process_own(monkeypatch, tmp_path):
    """/proc/self/cgroup names the process's own cgroup; its cap (or a parent's) is the one that counts."""
    from cs451 import limits
    own = tmp_path / "sys" / "memory" / "grader" / "job7"
    own.mkdir(parents=True)
    (own / "memory.limit_in_bytes").write_text(str(768 * 2**20))
    (tmp_path / "sys" / "memory" / "memory.limit_in_bytes").write_text("9223372036854771712")
    proc = tmp_path / "cgroup"
    proc.write_text("4:memory:/grader/job7\n0::/\n")
    real = Path.read_text

    def read(path: Path, *a, **k) -> str:
        text = str(path)
        if text == "/proc/self/cgroup":
            return real(proc)
        if text.startswith("/sys/fs/cgroup/memory/"):
            return real(tmp_path / "sys" / "memory" / Path(text).relative_to("/sys/fs/cgroup/memory"))
        raise OSError(2, "absent")
    monkeypatch.setattr(Path, "read_text", read)
    cap, where = limits._cgroup_limit()
    assert cap == 768 * 2**20 and where.endswith("grader/job7/memory.limit_in_bytes")


def test_scenes_schema_prints_the_schema_and_a_scene_may_point_at_it(tmp_path, capsys):
    from cs451.cli import main
    from cs451.scene_schema import SCHEMA_FILE
    assert main(["scenes", "--schema"]) == 0
    assert capsys.readouterr().out == SCHEMA_FILE.read_text()
    path = tmp_path / "pointing.json"
    path.write_text(json.dumps({"$schema": "../docs/scene.schema.json", **bundled("sphere")}))
    assert load_scene(path).name == "sphere"
    path.write_text(json.dumps({"$schema": 3, **bundled("sphere")}))
    with pytest.raises(KitError, match=r"\$schema: unknown field"):
        load_scene(path)
