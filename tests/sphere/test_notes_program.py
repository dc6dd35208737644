"""Stage 1 against its ground truth: the course notes' own lit-sphere program (notes §1), compiled and run.

``notes_sphere_fixture.c`` is the notes' listing with its two bugs fixed, a window size from the
command line and a frame dump (its header lists every change). It is built with gcc against
freeglut, GLU and Mesa, and run under Xvfb; what it draws must match ``cs451 render sphere`` within
the autograder's image tolerance at the notes' 500×500 and at other sizes and aspect ratios. The
same program with the light set before ``gluLookAt`` (in eye space, what the kit used to draw) must
not: that is what tells the light's space apart.

And S3: the matrices OpenGL's own glTranslate, glRotate, glScale, glPushMatrix and glPopMatrix leave on
the modelview stack (Mesa's fixed-function pipeline, tests/sphere/fixed_function.py) are the truth the
autograder's trimesh-built answers and the reference are held to, and Mesa's fixed-function render of
the orrery is what the kit draws with them.
"""
from __future__ import annotations

import json
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from PIL import Image

import fixed_function
from cs451.compare import ImageTolerance, compare_images

from conftest import assert_images_match
from cs451.grading.loader import load_tests
from cs451 import KIT_ROOT
from cs451.impl import load_impl
from cs451.scene import load_scene, parse_scene
from cs451.stages import sphere as s1

from autograder.sphere import truth as truths

FIXTURE = Path(__file__).with_name("notes_sphere_fixture.c")
#: the notes' window, and three others: wide, tall, and odd sizes with an aspect ratio that is not a simple fraction
SIZES = [(500, 500), (640, 360), (300, 500), (257, 193)]
#: what the fixture needs: a C compiler, freeglut's and GLU's headers and libraries, and an X server without a display
NEEDS = "gcc, freeglut3-dev and xvfb (apt-get install gcc freeglut3-dev xvfb; .ci/run installs them)"


def _build(source: str, folder: Path) -> Path:
    if not shutil.which("gcc") or not shutil.which("xvfb-run"):
        pytest.skip(f"needs {NEEDS}")
    c_file, program = folder / "notes_sphere.c", folder / "notes_sphere"
    c_file.write_text(source)
    done = subprocess.run(["gcc", "-O1", "-o", str(program), str(c_file), "-lglut", "-lGLU", "-lGL"],
                          capture_output=True, text=True)
    if done.returncode != 0:
        if "glut.h" in done.stderr or "-lglut" in done.stderr or "GL/" in done.stderr:
            pytest.skip(f"needs {NEEDS}: {done.stderr.strip().splitlines()[0]}")
        raise AssertionError(f"the fixture does not compile:\n{done.stderr}")
    return program


def _frames(program: Path, folder: Path) -> dict[tuple[int, int], np.ndarray]:
    """Run the program once per size under one Xvfb; each run draws one frame, writes it and exits."""
    script = " && ".join(f"{program} {w} {h} {folder}/{w}x{h}.ppm" for w, h in SIZES)
    done = subprocess.run(["xvfb-run", "-a", "-s", "-screen 0 1280x1024x24", "sh", "-c", script],
                          capture_output=True, text=True, timeout=240)
    assert done.returncode == 0, f"the notes' program failed under Xvfb:\n{done.stdout}{done.stderr}"
    return {(w, h): np.asarray(Image.open(folder / f"{w}x{h}.ppm"), dtype=np.float64) / 255.0 for w, h in SIZES}


@pytest.fixture(scope="module")
def notes_frames(tmp_path_factory) -> dict[str, dict[tuple[int, int], np.ndarray]]:
    """Frames of the notes' program as the notes write it, and of the same program with its light in eye space."""
    source = FIXTURE.read_text()
    light_call = "    glLightfv(GL_LIGHT0, GL_POSITION, position);\n"
    look_at_call = "    gluLookAt(0.0, 0.0, 8.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0); /* change 2 */\n"
    assert light_call in source and look_at_call in source
    eye_space = source.replace(light_call, "").replace(look_at_call, light_call + look_at_call)
    frames = {}
    for name, text in (("notes", source), ("eye-space light", eye_space)):
        folder = tmp_path_factory.mktemp(name.replace(" ", "-"))
        frames[name] = _frames(_build(text, folder), folder)
    return frames


def _reference():
    return load_impl(KIT_ROOT / "reference" / "sphere", "sphere")


def _kit_render(tmp_path: Path, size: tuple[int, int]) -> np.ndarray:
    """What ``cs451 render sphere -o s.png --size WxH`` writes, run as a user runs it."""
    out = tmp_path / f"kit-{size[0]}x{size[1]}.png"
    done = subprocess.run([sys.executable, "-m", "cs451.cli", "render", "sphere", "-o", str(out), "--impl",
                           str(KIT_ROOT / "reference"), "--size", f"{size[0]}x{size[1]}"], capture_output=True, text=True)
    assert done.returncode == 0, done.stderr
    return np.asarray(Image.open(out).convert("RGB"), dtype=np.float64) / 255.0


@pytest.mark.spawns
@pytest.mark.parametrize("size", SIZES, ids=[f"{w}x{h}" for w, h in SIZES])
def test01_cs451_render_sphere_matches_the_notes_program(notes_frames, tmp_path, size):
    notes, kit = notes_frames["notes"][size], _kit_render(tmp_path, size)
    assert_images_match(notes, kit, ImageTolerance(), f"notes-program-{size[0]}x{size[1]}", ("the notes' program", "cs451"))
    assert np.abs(notes - kit).max() <= 2 / 255 + 1e-9, "the kit and the notes' program should agree to rounding"


def test02_a_light_in_eye_space_is_a_different_picture(notes_frames):
    """The oracle can tell the light's space: the eye-space program fails the tolerance the notes' program passes."""
    notes, eye = notes_frames["notes"][(500, 500)], notes_frames["eye-space light"][(500, 500)]
    assert not compare_images(notes, eye, ImageTolerance()).passed
    data = json.loads(Path(load_scene("sphere").source).read_text())
    data["lights"][0]["space"] = "eye"   # the kit's scene option for a light fixed to the camera
    kit_eye = s1.render(parse_scene(data), _reference(), (500, 500))
    assert compare_images(eye, np.round(kit_eye * 255) / 255, ImageTolerance()).passed


# --- S3 against OpenGL's own matrix calls ------------------------------------------

def _model_view_tests():
    return [t for t in load_tests("sphere") if t.task == "S3"]


@pytest.fixture(scope="module")
def fixed():
    ok, reason = fixed_function.available()
    if not ok:
        pytest.skip(reason)


@pytest.mark.parametrize("test", _model_view_tests(), ids=lambda t: t.number)
def test03_the_s3_truth_and_the_reference_are_what_opengl_computes(fixed, test):
    """Mesa's modelview stack (float32) against the autograder's truth and the reference (float64)."""
    view, calls = np.asarray(test.params["view"], float), [tuple(c) for c in test.params["calls"]]
    mesa = fixed_function.model_view_matrices(view, calls)
    truth = truths.model_view_matrices(test.params)
    reference = _reference().model_view_matrices(view, calls)
    assert mesa.shape == truth.shape == reference.shape == (sum(c[0] == "draw" for c in calls), 4, 4)
    scale = max(1.0, float(np.abs(mesa).max()))
    assert np.abs(truth - mesa).max() <= 1e-6 * scale
    assert np.abs(reference - mesa).max() <= 1e-6 * scale
    np.testing.assert_allclose(reference, truth, rtol=1e-12, atol=1e-12)


def test04_the_orrery_is_drawn_as_the_fixed_function_pipeline_draws_it(fixed):
    """Nested groups with rotations, translations and a non-uniform glScale, lit per vertex by both."""
    scene = load_scene("orrery")
    impl = _reference()
    kit = np.round(s1.render(scene, impl, (400, 400), shading="gouraud") * 255) / 255
    truth = fixed_function.render(scene, (400, 400))
    assert_images_match(truth, kit, ImageTolerance(), "orrery", ("fixed-function", "cs451"))
    assert (truth.max(axis=2) > 0.05).mean() > 0.03, "the orrery should fill part of the frame"
    # and the comparison sees the transforms: the same calls each multiplied on the left put the planets elsewhere
    cam = scene.camera
    view = impl.look_at(cam.eye, cam.center, cam.up)
    stack, wrong = [np.eye(4)], []
    for name, *args in s1.drawing_calls(scene):
        if name == "push":
            stack.append(stack[-1])
        elif name == "pop":
            stack.pop()
        elif name == "draw":
            wrong.append(view @ stack[-1])
        else:
            stack[-1] = truths._gl_matrix(name, *args) @ stack[-1]
    viewport, projection = impl.reshape(400, 400, cam)
    misplaced = s1.render(scene, impl, (400, 400), shading="gouraud",
                          given={"viewport": viewport, "projection": projection, "view": view, "model_views": np.array(wrong)})
    assert not compare_images(truth, np.round(misplaced * 255) / 255, ImageTolerance()).passed
