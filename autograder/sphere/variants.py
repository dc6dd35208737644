"""Stage 1's fresh cases: each public test's case with new numbers of the same kind. Not shipped to students.

The kit grades the public tests on these wherever it grades with the hidden tests (a roster, the
Gradescope zip), drawn from its private secret (:func:`cs451.grading.loader.fresh_case`), so the
answers a release ships to the shipped cases answer nothing there. Each keeps its case's purpose:
a square window stays square and a minimised one keeps height 0, a coarse sphere stays coarse,
a mirror stays a mirror, a press that changes nothing still changes nothing.
"""
from __future__ import annotations

import copy

import numpy as np

from cs451.grading.spec import Case

from autograder.fresh import colour, dimmed, num, scaled
from autograder.sphere import truth as truths


def perspective(p: dict, rng: np.random.Generator) -> Case:
    """Another field of view, near and far; a square window stays square, a wide one wide."""
    fovy, near = num(rng.uniform(20, 75), 3), num(rng.uniform(0.1, 3))
    aspect = 1.0 if p["aspect"] == 1.0 else num(rng.uniform(1.2, 2.4))
    far = num(near * rng.uniform(10, 200), 3)
    return Case({"fovy": fovy, "aspect": aspect, "near": near, "far": far},
                f"fovy {fovy:g}°, aspect {aspect:g}, near {near:g}, far {far:g}")


def look_at(p: dict, rng: np.random.Generator) -> Case:
    """A camera on the z axis stays on it (another distance); an oblique one moves elsewhere, y still up."""
    eye, center = np.asarray(p["eye"], float), np.asarray(p["center"], float)
    if np.allclose(eye[:2], center[:2]):
        c = num(rng.uniform(-2, 2))
        center, eye = [0.0, 0.0, c], [0.0, 0.0, num(c + rng.uniform(4, 12))]
    else:
        center = np.round(rng.uniform(-2, 2, 3), 4).tolist()
        direction = rng.normal(size=3)
        direction[1] *= 0.5                   # never along the up vector
        eye = np.round(np.asarray(center) + direction / np.linalg.norm(direction) * rng.uniform(4, 10), 4).tolist()
    return Case({"eye": eye, "center": center, "up": p["up"]}, f"eye {eye}, center {center}, up {p['up']}")


def model_view_matrices(p: dict, rng: np.random.Generator) -> Case:
    """The same calls in the same order with other amounts (zeros and signs kept), on a view another distance away."""
    view = copy.deepcopy(p["view"])
    view[2][3] = num(-rng.uniform(4, 12))
    calls = [[c[0], *scaled(c[1:], rng)] if len(c) > 1 else list(c) for c in p["calls"]]
    shown = "; ".join(f"{c[0]}({', '.join(f'{v:g}' for v in c[1:])})" if len(c) > 1 else c[0] for c in calls[:6])
    return Case({"view": view, "calls": calls},
                f"view translated by {view[2][3]:g} along z, calls {shown}{' …' if len(calls) > 6 else ''}")


def sphere_mesh(p: dict, rng: np.random.Generator) -> Case:
    """Another radius and tessellation; a coarse sphere stays coarse."""
    coarse = p["slices"] <= 10
    radius = num(rng.uniform(0.5, 2.5))
    slices = int(rng.integers(5, 12) if coarse else rng.integers(20, 49))
    stacks = int(rng.integers(3, 8) if coarse else rng.integers(20, 49))
    if (slices, stacks) == (p["slices"], p["stacks"]):
        slices += 1
    return Case({"radius": radius, "slices": slices, "stacks": stacks},
                f"glutSolidSphere({radius:g}, {slices}, {stacks})")


def _fresh_scene(scene: dict, rng: np.random.Generator) -> dict:
    """The scene's objects kept (their tessellation too); lights moved and recoloured, materials recoloured,
    the camera nearer or farther."""
    scene = copy.deepcopy(scene)
    cam = scene["camera"]
    cam["eye"] = np.round(np.asarray(cam["eye"], float) * rng.uniform(0.88, 1.12)
                          + np.r_[rng.uniform(-0.6, 0.6, 2), 0.0], 4).tolist()
    scene["ambient"] = np.round(np.clip(np.asarray(scene.get("ambient", [0.2] * 3)) * rng.uniform(0.5, 1.5, 3), 0, 0.4),
                                3).tolist()
    for light in scene["lights"]:
        for key in ("position", "direction"):
            if key in light:
                v = np.asarray(light[key], float)
                light[key] = np.round(v + rng.uniform(-0.2, 0.2, 3) * np.linalg.norm(v), 4).tolist()
        for key in ("diffuse", "specular", "ambient"):
            if key in light:
                light[key] = dimmed(light[key], rng)
        if "attenuation" in light:
            light["attenuation"] = scaled(light["attenuation"], rng, 0.7, 1.3)
    for material in scene["materials"].values():
        material["diffuse"] = colour(material.get("diffuse", [0.8] * 3), rng)
        for key in ("specular", "emission", "ambient"):
            if key in material:
                material[key] = np.round(np.clip(np.asarray(material[key]) * rng.uniform(0.6, 1.4, 3), 0, 1), 3).tolist()
        if "shininess" in material:
            material["shininess"] = num(min(128.0, material["shininess"] * rng.uniform(0.6, 1.5)), 2)
    return scene


def _size(size: list, rng: np.random.Generator) -> list:
    w, h = size
    if w == h:
        s = int(rng.integers(int(0.8 * w), int(1.05 * w)))
        return [s, s]
    nw = int(w * rng.uniform(0.85, 1.15))
    nh = int(nw * h / w * rng.uniform(0.9, 1.1))
    return [nw, nh if nh != nw else nh + 1]


def render(p: dict, rng: np.random.Generator) -> Case:
    """The scene's spheres as they are; lights, colours, camera distance and window size fresh."""
    scene = _fresh_scene(p["scene"], rng)
    size = _size(p["size"], rng)
    light = scene["lights"][0]
    where = light.get("position", light.get("direction"))
    materials = ", ".join(f"{name} diffuse {m['diffuse']}" for name, m in scene["materials"].items())
    return Case({**p, "scene": scene, "size": size},
                f"{size[0]}×{size[1]}, eye {scene['camera']['eye']}, first light at {where}, materials {materials}")


def reshape(p: dict, rng: np.random.Generator) -> Case:
    """Another window of the same shape (square, wide, or of height 0) and another field of view."""
    w, h = p["width"], p["height"]
    if h == 0:
        w = int(rng.integers(100, 1201))
    elif w == h:
        w = h = int(rng.integers(200, 1001))
    else:
        h = int(rng.integers(150, 501))
        w = int(rng.integers(int(1.8 * h), int(3 * h)))
    camera = {**p["camera"], "fovy": num(rng.uniform(20, 70), 3)}
    return Case({**p, "width": w, "height": h, "camera": camera}, f"a {w}×{h} window, fovy {camera['fovy']:g}°")


def handle_key(p: dict, rng: np.random.Generator) -> Case:
    """The same keys on other states: a state at a limit (4 or 256) stays there, so each press changes the state
    exactly when the shipped one did."""
    presses = []
    for key, state in p["presses"]:
        fresh = dict(state)
        for field in ("slices", "stacks"):
            if state[field] not in (4, 256):
                fresh[field] = int(rng.integers(5, 256))
        fresh["shading"] = str(rng.choice(["gouraud", "phong"]))
        changed, was = truths.key_truth(key, fresh) != fresh, truths.key_truth(key, state) != state
        presses.append([key, fresh if changed == was else dict(state)])
    shown = "; ".join(f"{k!r} on {s['slices']}×{s['stacks']} {s['shading']}" for k, s in presses)
    return Case({"presses": presses}, shown)


def stereo_pair(p: dict, rng: np.random.Generator) -> Case:
    """Another field of view, window, eye separation and convergence distance."""
    fovy, aspect, near = num(rng.uniform(20, 75), 3), num(rng.uniform(1.0, 2.4)), num(rng.uniform(0.1, 2))
    far, separation = num(near * rng.uniform(10, 200), 3), num(rng.uniform(0.03, 0.5))
    convergence = num(near * rng.uniform(2, 10))
    return Case({"fovy": fovy, "aspect": aspect, "near": near, "far": far, "separation": separation,
                 "convergence": convergence},
                f"fovy {fovy:g}°, aspect {aspect:g}, near {near:g}, far {far:g}, separation {separation:g}, "
                f"convergence {convergence:g}")
