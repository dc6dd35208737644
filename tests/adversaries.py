"""Hostile submissions for the attack tests: packages that do nothing, and packages made of what a release ships.

A *vacuous* submission defines every task with the least answer of the right
form (identity matrices, empty meshes, misses, unchanged inputs): a grader whose
checks can pass on nothing gives it points. A *scavenger* submission answers every
task by calling whatever the student release ships (the engine ``cs451``, the
stage's ``checks.py``) whose name or parameters look like the task's: a release
that ships an answer gives it points. Both must score 0.
"""
from __future__ import annotations

import shutil
from pathlib import Path

from cs451.stages import get_stage

#: Each task's least answer of the right form, as the body of its function.
VACUOUS = {
    "perspective": "return np.eye(4)",
    "look_at": "return np.eye(4)",
    "sphere_mesh": "return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), dtype=int)",
    "gouraud_shaders": "return VS, FS",
    "phong_shaders": "return VS, FS",
    "reshape": "return (0, 0, 0, 0), np.eye(4)",
    "handle_key": "return state",
    "camera_rays": "n = width * height\n    return np.tile(np.asarray(camera.eye, float), (n, 1)), np.tile([0.0, 0.0, -1.0], (n, 1))",
    "intersect_sphere": "n = len(origins)\n    return np.full(n, np.inf), np.full(n, np.inf)",
    "intersect_triangle": "return np.full(len(origins), np.inf)",
    "build_bvh": ("n = len(lo)\n    return {'lo': lo.min(axis=0)[None], 'hi': hi.max(axis=0)[None], 'child': np.array([-1]),"
                  " 'start': np.array([0]), 'count': np.array([n]), 'order': np.arange(n)}"),
    "closest_hit": "n = len(origins)\n    return np.full(n, np.inf), np.full(n, -1), np.zeros((n, 3))",
    "local_shading": "return np.zeros((len(normals), 3))",
    "shadow_transmission": "scene.counters['shadow'] += len(origins)\n    return np.ones((len(origins), 3))",
    "reflect": "return np.asarray(directions, float)",
    "refract": "d = np.asarray(directions, float)\n    return d, np.zeros(len(d), bool)",
    "fresnel": "return np.zeros(np.shape(cos_i))",
    "trace": "scene.counters['camera'] += len(origins)\n    return np.zeros((len(origins), 3))",
    "delta_form_factors": "r = int(resolution)\n    return np.zeros((r, r)), np.zeros((r // 2, r))",
    "hemicube_views": "return np.stack([np.eye(4)] * 5)",
    "hemicube_projections": "return np.stack([np.eye(4)] * 2)",
    "item_buffer_shaders": "return ITEM_VS, ITEM_FS",
    "form_factor_row": "return np.zeros(n_patches)",
    "point_polygon_form_factor": "return 0.0",
    "model_view_matrices": "return np.zeros((sum(1 for c in calls if c[0] == 'draw'), 4, 4))",
    "subdivide": "q = np.asarray(quads, float)\n    return q.copy(), np.arange(len(q))",
    "shoot": "return np.array(radiosity, float), np.array(unshot, float)",
    "progressive_refinement": "return np.array(emission, float), np.zeros_like(np.array(emission, float)), []",
    "ambient_term": "return np.zeros(3)",
    "vertex_colors": ("q = np.asarray(quads, float)\n    return q.reshape(-1, 3), np.repeat(np.asarray(radiosity, float), 4, axis=0),"
                      " np.arange(4 * len(q)).reshape(-1, 4)"),
}

HEADER = '''"""A submission that does nothing: the least answer of the right form for every task."""
import numpy as np

VS = "void main() { gl_Position = u_projection * u_model_view * vec4(in_position, 1.0); }"
FS = "void main() { frag_color = vec4(0.0, 0.0, 0.0, 1.0); }"
ITEM_VS = "void main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); }"
ITEM_FS = "void main() { item = 0u; }"
'''


def _define(task, body: str) -> str:
    return f"\n\ndef {task.function}({', '.join(task.params)}):\n    {body}\n"


def vacuous(stage: str, root: Path) -> Path:
    """A folder holding ``<stage>/__init__.py`` with every task answered by nothing."""
    text = HEADER + "".join(_define(t, VACUOUS[t.function]) for t in get_stage(stage).tasks)
    (root / stage).mkdir(parents=True)
    (root / stage / "__init__.py").write_text(text)
    return root


SCAVENGER = '''"""A submission made of what the student release ships: each task tries the shipped functions that look like it."""
import importlib
import inspect
import pkgutil
import signal

import cs451

from . import shipped_checks


def _shipped():
    modules = [shipped_checks]
    for info in pkgutil.walk_packages(cs451.__path__, "cs451."):
        try:
            modules.append(importlib.import_module(info.name))
        except BaseException:
            continue
    seen = {}
    for module in modules:
        for name, fn in vars(module).items():
            if inspect.isfunction(fn) and fn.__module__ == module.__name__:
                seen[(module.__name__, name)] = fn
    return list(seen.values())


def _candidates(task_name, params):
    words = set(task_name.split("_"))
    found = []
    for fn in _shipped():
        try:
            names = tuple(inspect.signature(fn).parameters)
        except (TypeError, ValueError):
            continue
        if fn.__name__.strip("_") == task_name or names[:len(params)] == params or words & set(fn.__name__.strip("_").split("_")):
            found.append(fn)
    found.sort(key=lambda fn: (fn.__name__.strip("_") != task_name, -len(words & set(fn.__name__.split("_")))))
    return found[:12]


class _Late(Exception):
    pass


def _late(*_):
    raise _Late()


def _scavenge(task_name, params, args):
    signal.signal(signal.SIGALRM, _late)
    for fn in _candidates(task_name, params):
        signal.setitimer(signal.ITIMER_REAL, 0.5)
        try:
            return fn(*args)
        except BaseException:
            continue
        finally:
            signal.setitimer(signal.ITIMER_REAL, 0)
    raise NotImplementedError(f"nothing shipped answers {task_name}")
'''


def scavenger(stage: str, release: Path, root: Path) -> Path:
    """A folder holding ``<stage>/`` whose every task is answered by the release's shipped functions, if any does."""
    pkg = root / stage
    pkg.mkdir(parents=True)
    shutil.copy(release / "autograder" / stage / "checks.py", pkg / "shipped_checks.py")
    text = SCAVENGER + "".join(
        f"\n\ndef {t.function}({', '.join(t.params)}):\n"
        f"    return _scavenge({t.function!r}, {tuple(t.params)!r}, ({''.join(p + ', ' for p in t.params)}))\n"
        for t in get_stage(stage).tasks)
    (pkg / "__init__.py").write_text(text)
    return root


def shipped_python(release: Path) -> list[Path]:
    """Every Python file of a release (what a student gets)."""
    return sorted(p for p in release.rglob("*.py") if ".venv" not in p.parts)


def task_answer_definitions(release: Path, stage: str) -> list[str]:
    """Places in a release outside the student's own package that define a function named after a task."""
    names = {t.function for t in get_stage(stage).tasks}
    found = []
    for path in shipped_python(release):
        if path.relative_to(release).parts[0] == stage:
            continue  # the starter: stubs by design
        for lineno, line in enumerate(path.read_text().splitlines(), 1):
            stripped = line.strip()
            if stripped.startswith("def ") and stripped[4:].split("(")[0] in names:
                found.append(f"{path.relative_to(release)}:{lineno}: {stripped}")
    return found


