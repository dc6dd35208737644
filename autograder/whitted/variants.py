"""Stage 2's fresh cases: each public test's case with new numbers of the same kind. Not shipped to students.

Graded instead of the shipped cases wherever the kit grades with its hidden tests (see
``autograder/sphere/variants.py``). Each keeps its case's purpose: intersection tests are turned,
scaled and moved as a whole (a hit stays a hit, a grazing ray grazes, a ray from inside stays
inside, a zero-area triangle stays degenerate, a ray through a shared edge still goes through it),
with every ray's direction of another length so that no distance stays the same; a rolled camera
stays rolled, a light under the floor stays under it, no mirror appears where there was none, and
the mirrors' counts are computed again for their fresh reflectance and limits.
"""
from __future__ import annotations

import copy

import numpy as np

from cs451.grading.spec import Case

from autograder.fresh import Similarity, box_description, colour, fresh_box, num, rotation


def _unit(v: np.ndarray) -> np.ndarray:
    return v / np.linalg.norm(v, axis=-1, keepdims=True)


def camera(p: dict, rng: np.random.Generator) -> Case:
    """The camera moved and its field of view changed; a rolled camera (up not perpendicular) stays rolled, a tall
    image tall."""
    cam = copy.deepcopy(p["camera"])
    eye, center = np.asarray(cam["eye"], float), np.asarray(cam["center"], float)
    reach = 0.15 * float(np.linalg.norm(eye - center))
    cam["eye"] = np.round(eye + rng.uniform(-reach, reach, 3), 4).tolist()
    cam["center"] = np.round(center + rng.uniform(-reach, reach, 3) / 2, 4).tolist()
    cam["fovy"] = num(rng.uniform(30, 70), 3)
    view = _unit(np.asarray(cam["center"]) - np.asarray(cam["eye"]))
    if list(cam.get("up", [0, 1, 0])) != [0, 1, 0]:          # rolled: a fresh tilted up
        up = np.r_[rng.uniform(-0.6, 0.6), 1.0, rng.uniform(-0.6, 0.6)]
        up = up if abs(float(_unit(up) @ view)) > 0.05 else up + [0.3, 0, 0.3]
        cam["up"] = np.round(up, 4).tolist()
    w, h = p["width"], p["height"]
    if h > w:
        width = int(rng.integers(4, 7))
        height = int(rng.integers(width + 1, width + 4))
    else:
        width = int(rng.integers(6, 11))
        height = int(rng.integers(4, width))
    return Case({"camera": cam, "width": width, "height": height},
                f"{width}×{height}, eye {cam['eye']}, center {cam['center']}, up {cam.get('up', [0, 1, 0])}, "
                f"fovy {cam['fovy']:g}°")


def _rays(p: dict, move: Similarity, rng: np.random.Generator) -> tuple[list, list]:
    lengths = rng.uniform(0.5, 2.0, (len(p["directions"]), 1))
    return ([move.point(o) for o in p["origins"]],
            (np.asarray([move.vector(d) for d in p["directions"]]) * lengths).tolist())


def intersect_sphere(p: dict, rng: np.random.Generator) -> Case:
    """The sphere and its rays turned, scaled and moved as a whole; each direction of another length."""
    move = Similarity(rng, shift=2.0 if p["radius"] > 0.01 else 0.0)   # a far sphere stays far from the origins
    origins, directions = _rays(p, move, rng)
    center, radius = move.point(p["center"]), move.length(p["radius"])
    return Case({"center": center, "radius": radius, "origins": origins, "directions": directions},
                f"a sphere of radius {radius:.4g} at {np.round(center, 4).tolist()}, {len(origins)} rays, the "
                f"shipped case turned, scaled by {move.s:.3g} and moved")


def sphere_exact(p: dict, rng: np.random.Generator) -> Case:
    """The sphere and its rays with axes swapped and flipped and lengths scaled by a power of two (exact in floating
    point, so a tangent ray stays exactly tangent), then moved by a whole number along each axis; directions scaled
    by powers of two too."""
    move = ExactMove(rng)
    shift = rng.integers(-4, 5, 3).astype(float)
    origins = (np.asarray(move.point(p["origins"])) + shift).tolist()
    directions = (np.asarray(move.vector(p["directions"])) * 2.0 ** rng.integers(-1, 2, (len(p["directions"]), 1))).tolist()
    center = (np.asarray(move.point(p["center"])) + shift).tolist()
    return Case({"center": center, "radius": p["radius"] * move.scale, "origins": origins, "directions": directions},
                f"a sphere of radius {p['radius'] * move.scale:g} at {center}, {len(origins)} rays tangent or through it")


class ExactMove:
    """Axes swapped and flipped and lengths scaled by a power of two: exact in floating point, so a ray exactly on an
    edge (or through a polygon's diagonal) stays exactly on it and a degenerate triangle stays degenerate."""

    def __init__(self, rng: np.random.Generator):
        self.axes, self.signs = rng.permutation(3), rng.choice([-1.0, 1.0], 3)
        self.scale = float(2.0 ** rng.choice([-1, 1, 2]))

    def point(self, v: list) -> list:
        return (np.asarray(v, float)[..., self.axes] * self.signs * self.scale).tolist()

    def vector(self, v: list) -> list:
        return (np.asarray(v, float)[..., self.axes] * self.signs).tolist()

    def __str__(self) -> str:
        return (f"axes {''.join('xyz'[a] for a in self.axes)} as xyz, signs {self.signs.astype(int).tolist()}, "
                f"scaled by {self.scale:g}")


def intersect_triangle(p: dict, rng: np.random.Generator) -> Case:
    """Zero-area triangles and their rays moved exactly (:class:`ExactMove`), so each stays degenerate; each direction
    scaled by its own power of two."""
    move = ExactMove(rng)
    n = len(p["origins"])
    directions = (np.asarray(move.point(p["directions"])) * 2.0 ** rng.integers(-1, 3, (n, 1))).tolist()
    corners = {k: move.point(p[k]) for k in ("v0", "v1", "v2")}
    return Case({"origins": move.point(p["origins"]), "directions": directions, **corners},
                f"{n} rays and triangles: the shipped case with {move}, directions of other lengths")


def _dyadic(rng: np.random.Generator, lo: float, hi: float, shape=(), denominator: int = 64) -> np.ndarray:
    """Random numbers that are multiples of 1/denominator: sums and products of a few stay exact in floating point."""
    return np.round(rng.uniform(lo, hi, shape) * denominator) / denominator


def triangle_rays(p: dict, rng: np.random.Generator) -> Case:
    """A fresh triangle and the shipped case's six kinds of ray, built in exact (dyadic) arithmetic: a hit from the
    front, a miss beside it, a hit from behind, a ray pointing away, a ray exactly through an edge, a parallel ray, a
    ray that starts on the triangle (t = 0: a miss)."""
    while True:
        v0, v1, v2 = (_dyadic(rng, -2, 2, 3) for _ in range(3))
        e1, e2 = v1 - v0, v2 - v0
        n = np.cross(e1, e2)
        if np.linalg.norm(n) > 0.5:
            break

    def at(b1: float, b2: float) -> np.ndarray:
        return v0 + b1 * e1 + b2 * e2
    h = _dyadic(rng, 0.5, 2.0, 6, 8)
    inside = [at(*_dyadic(rng, 0.1, 0.4, 2, 16)) for _ in range(4)]
    edge = at(0.5, 0.0)
    shift = _dyadic(rng, -0.5, 0.5, 1, 8)[0] * e2
    origins = [inside[0] + h[0] * n, at(0.625, 0.625) + h[1] * n, inside[1] - h[2] * n, inside[2] + h[3] * n,
               edge + h[4] * n + shift, inside[3] + h[5] * n]
    directions = [-n, -n, n, n, edge - origins[4], e1]
    lengths = 2.0 ** rng.integers(-1, 3, 6)
    directions = [d * k for d, k in zip(directions, lengths)]
    rays = len(origins)
    # a ray that starts on a triangle in a plane z = c (dyadic, so t = 0 exactly in floating point too): a miss
    c = _dyadic(rng, -2, 2, 1)[0]
    flat = [np.array([0.0, 0.0, c]), np.array([1.0, 0.0, c]), np.array([0.0, 1.0, c])]
    origins.append(np.array([*_dyadic(rng, 0.125, 0.375, 2, 8), c]))
    directions.append(np.array([0.0, 0.0, float(rng.choice([-1.0, 1.0]))]))
    corners = [[v.tolist()] * rays + [f.tolist()] for v, f in zip((v0, v1, v2), flat)]
    return Case({"origins": np.asarray(origins).tolist(), "directions": np.asarray(directions).tolist(),
                 "v0": corners[0], "v1": corners[1], "v2": corners[2]},
                f"the triangle {v0.tolist()}, {v1.tolist()}, {v2.tolist()}: a hit from the front, a miss beside it, a hit "
                "from behind, a ray pointing away, a ray through the edge v0-v1, a parallel ray, a ray starting on it")


def fan(p: dict, rng: np.random.Generator) -> Case:
    """A fresh fan of another number of triangles (its corners jittered, its ripple another height), rays from another
    point through its shared edges and vertices; the check counts the fresh rays and triangles."""
    from autograder.whitted.public import watertight_test
    sides = int(rng.choice([5, 7, 8]))
    angles = np.linspace(0, 2 * np.pi, sides + 1)[:-1] + rng.uniform(-0.2, 0.2, sides)
    radius, ripple = rng.uniform(0.7, 1.3, sides), rng.uniform(0.02, 0.2)
    corners = [[float(r * np.cos(a)), float(r * np.sin(a)), float(ripple * np.sin(3 * a))] for r, a in zip(radius, angles)]
    side = 1.0 if p["origins"][0][2] > 0 else -1.0       # the shipped fan's side: in front, or behind (clockwise)
    center = [num(rng.uniform(-0.3, 0.3)), num(rng.uniform(-0.3, 0.3)), num(side * rng.uniform(2.5, 3.5))]
    test = watertight_test("fresh", 1, center, corners)
    return Case(test.params, f"a fan of {sides} triangles seen from {center}", test.check)


def grid_edges(p: dict, rng: np.random.Generator) -> Case:
    """Another grid of squares (2 or 3 a side, 1/8 to 1/2 wide, at another offset of small multiples of 1/8), its
    triangles wound as the shipped ones, rays exactly on its edges and vertices."""
    from autograder.whitted.public import grid_edge_test
    cells, scale = int(rng.integers(2, 4)), float(2.0 ** -int(rng.integers(1, 4)))   # edge functions below 1
    offset = (rng.integers(-16, 17, 3) / 8.0).tolist()
    a, b, c = (np.asarray(p[k][0], float) for k in ("v0", "v1", "v2"))
    clockwise = bool(np.cross(b - a, c - a)[2] < 0)
    test = grid_edge_test("fresh", 1, cells, scale, offset, clockwise)
    return Case(test.params, f"a {cells} × {cells} grid {scale:g} a cell at {offset}, its triangles "
                             f"{'clockwise' if clockwise else 'counter-clockwise'}", test.check)


def build_bvh(p: dict, rng: np.random.Generator) -> Case:
    """As many fresh random boxes, in a region of another size; or the scene's spheres and polygons scaled and moved."""
    if "scene" in p:
        return _moved_scene(p, rng)
    n, extent = len(p["lo"]), rng.uniform(5, 20)
    lo = rng.uniform(-extent, extent, (n, 3))
    hi = lo + rng.uniform(0.1, 2.0, (n, 3))
    return Case({"lo": np.round(lo, 6).tolist(), "hi": np.round(hi, 6).tolist()},
                f"{n} random boxes 0.1 to 2 wide in a cube of half-side {extent:.3g}")


def _moved_scene(p: dict, rng: np.random.Generator) -> Case:
    """The scene's spheres and polygons scaled by one factor and moved by one offset (the hierarchy's shape kept)."""
    scene = copy.deepcopy(p["scene"])
    scale, offset = num(rng.uniform(0.5, 2.0), 3), np.round(rng.uniform(-50, 50, 3), 3)
    for obj in scene["objects"]:
        if obj["type"] == "sphere":
            obj["center"] = np.round(scale * np.asarray(obj["center"], float) + offset, 6).tolist()
            obj["radius"] = num(scale * obj["radius"], 6)
        elif obj["type"] == "polygon":
            obj["vertices"] = np.round(scale * np.asarray(obj["vertices"], float) + offset, 6).tolist()
    return Case({**p, "scene": scene}, f"the scene scaled by {scale:g} and moved by {offset.tolist()}")


def closest_hit_image(p: dict, rng: np.random.Generator) -> Case:
    """The same scene with fresh colours and lights, seen from a little elsewhere, at another size."""
    scene = fresh_box(p["scene"], rng)
    w, h = p["size"]
    s = int(w * rng.uniform(0.85, 1.12))
    size = [s, s] if w == h else [s, max(4, round(s * h / w))]
    return Case({**p, "scene": scene, "size": size}, f"{size[0]}×{size[1]}; {box_description(scene)}")


def closest_hit_rays(p: dict, rng: np.random.Generator) -> Case:
    """Fresh rays of the same kinds in the same scene: from around it, and from inside its glass sphere."""
    rays = p["rays"]
    origins = np.asarray(rays["origins"], float)
    spheres = [o for o in p["scene"]["objects"] if o["type"] == "sphere"]
    inside = [s for s in spheres if np.linalg.norm(origins[-1] - s["center"]) < s["radius"]][0]
    n_in = int(sum(np.linalg.norm(o - inside["center"]) < inside["radius"] for o in origins))
    n_out = len(origins) - n_in
    lo, hi = origins[:n_out].min(axis=0), origins[:n_out].max(axis=0)
    around = rng.uniform(lo, hi, (n_out, 3))
    offsets = _unit(rng.normal(size=(n_in, 3))) * rng.uniform(0, 0.6, (n_in, 1)) * inside["radius"]
    fresh = np.r_[around, np.asarray(inside["center"]) + offsets]
    directions = _unit(rng.normal(size=(len(fresh), 3)))
    return Case({**p, "rays": {"origins": np.round(fresh, 6).tolist(), "directions": np.round(directions, 9).tolist()}},
                f"{n_out} fresh rays from around the scene and {n_in} from inside the sphere at {inside['center']}")


def local_shading(p: dict, rng: np.random.Generator) -> Case:
    """As many fresh random points, lights and materials."""
    n = len(p["normals"])
    out = {k: np.round(_unit(rng.normal(size=(n, 3))), 12).tolist() for k in ("normals", "to_eye", "to_light")}
    for k in ("light_diffuse", "light_specular", "diffuse", "specular"):
        out[k] = np.round(rng.uniform(0, 1, (n, 3)), 6).tolist()
    out["shininess"] = rng.choice([0.0, 1.0, 8.0, 50.0, 128.0], n).tolist()
    return Case(out, f"{n} fresh random points, lights and materials")


def grazing(p: dict, rng: np.random.Generator) -> Case:
    """Fresh lights exactly square to their normals: each normal an axis, the light a fresh unit vector with no
    component along it (so n·l is exactly 0), the eye a fresh direction in front; the last two lights in front
    (lit as usual); fresh colours."""
    n = len(p["normals"])
    axes = rng.integers(0, 3, n)
    normals, lights, eyes = np.zeros((n, 3)), rng.normal(size=(n, 3)), rng.normal(size=(n, 3))
    normals[np.arange(n), axes] = 1.0
    lights[np.arange(n), axes] = 0.0
    last = np.arange(n - 2, n)
    lights[last, axes[last]] = np.abs(rng.normal(size=2)) + 0.5
    eyes[np.arange(n), axes] = np.abs(eyes[np.arange(n), axes]) + 0.5
    out = {"normals": normals.tolist(), "to_light": np.round(_unit(lights), 12).tolist(),
           "to_eye": np.round(_unit(eyes), 12).tolist()}
    for k in ("light_diffuse", "light_specular", "diffuse", "specular"):
        out[k] = np.round(rng.uniform(0.2, 1, (n, 3)), 6).tolist()
    out["shininess"] = rng.choice([0.0, 1.0, 8.0], n).tolist()
    return Case(out, f"{n - 2} fresh lights exactly at grazing and 2 lit ones")


def shadow_transmission(p: dict, rng: np.random.Generator) -> Case:
    """Fresh transmittances; a scene without a checkerboard turned, scaled and moved with its segments as a whole,
    a checkerboard crossed by fresh segments."""
    scene = copy.deepcopy(p["scene"])
    for material in scene["materials"].values():
        if "transmittance" in material:
            material["transmittance"] = colour(material["transmittance"], rng, 0.1, 0.9)
    if any(o.get("checker") for o in scene["objects"]):
        n = len(p["origins"])
        x = rng.uniform(-3, 3, (n, 2))
        origins = np.c_[x[:, 0], np.full(n, -1.0), x[:, 1]]
        targets = np.c_[x[:, 0] + rng.uniform(-0.5, 0.5, n), np.full(n, 2.0), x[:, 1] + rng.uniform(-0.5, 0.5, n)]
        params = {"scene": scene, "origins": np.round(origins, 6).tolist(), "targets": np.round(targets, 6).tolist()}
        shown = f"{n} fresh segments across the checkerboard"
    else:
        move = ExactMove(rng)    # a segment through a polygon's diagonal stays exactly on it (it crosses it once)
        for light in scene["lights"]:
            light["position"] = move.point(light["position"])
        for obj in scene["objects"]:
            if obj["type"] == "sphere":
                obj["center"], obj["radius"] = move.point(obj["center"]), move.scale * obj["radius"]
            elif obj["type"] == "polygon":
                obj["vertices"] = [move.point(v) for v in obj["vertices"]]
            elif obj["type"] == "plane":
                obj["point"], obj["normal"] = move.point(obj["point"]), move.vector(obj["normal"])
        params = {"scene": scene, "origins": [move.point(o) for o in p["origins"]],
                  "targets": [move.point(t) for t in p["targets"]]}
        shown = f"the scene and its {len(p['origins'])} segments with {move}"
    colours = ", ".join(f"{k} {m['transmittance']}" for k, m in scene["materials"].items() if "transmittance" in m)
    return Case(params, f"{shown}; transmittances {colours}")


def reflect(p: dict, rng: np.random.Generator) -> Case:
    """As many fresh directions, each with a normal facing it."""
    n = len(p["directions"])
    d = _unit(rng.normal(size=(n, 3)))
    normals = _unit(-d + rng.normal(size=(n, 3)) * 0.4)
    return Case({"directions": np.round(d, 12).tolist(), "normals": np.round(normals, 12).tolist()},
                f"{n} fresh directions and normals")


def refract(p: dict, rng: np.random.Generator) -> Case:
    """Fresh directions onto a turned surface, another index of the same side (into glass, or out of it with some
    rays past the critical angle)."""
    n = len(p["directions"])
    if isinstance(p["eta"], list):
        return _refract_per_ray(p, rng)
    out_of_glass = p["eta"] > 1
    turn = rotation(rng)
    while True:
        eta = num(rng.uniform(1.3, 1.8) if out_of_glass else 1 / rng.uniform(1.3, 1.8), 9)
        local = _unit(rng.normal(size=(n, 3)) + [0, 0, -1.5])
        cos_i = -local[:, 2]
        tir = eta ** 2 * (1 - cos_i ** 2) > 1
        if tir.any() == out_of_glass and not tir.all():
            break
    return Case({"directions": np.round(local @ turn.T, 12).tolist(),
                 "normals": np.round(np.tile(turn[:, 2], (n, 1)), 12).tolist(), "eta": eta},
                f"{n} fresh directions, η = {eta:.4g}{f', {int(tir.sum())} past the critical angle' if tir.any() else ''}")


def _refract_per_ray(p: dict, rng: np.random.Generator) -> Case:
    """One η per ray: fresh directions onto a turned surface, each ray keeping its kind of η (below 1, 1, above 1)."""
    eta = np.asarray(p["eta"], float)
    fresh = np.where(eta > 1, rng.uniform(1.3, 1.8, len(eta)), np.where(eta < 1, 1 / rng.uniform(1.3, 1.8, len(eta)), 1.0))
    turn = rotation(rng)
    local = _unit(rng.normal(size=(len(eta), 3)) + [0, 0, -1.5])
    return Case({"directions": np.round(local @ turn.T, 12).tolist(),
                 "normals": np.round(np.tile(turn[:, 2], (len(eta), 1)), 12).tolist(), "eta": np.round(fresh, 9).tolist()},
                f"{len(eta)} fresh directions, one η per ray ({int((eta == 1).sum())} of them 1)")


def refract_grazing(p: dict, rng: np.random.Generator) -> Case:
    """Fresh directions for the rays of η ≠ 1; the grazing rays of η = 1 (d·n = 0, so sin²θt = 1 exactly) and every
    normal moved with axes swapped and flipped, which keeps them exact."""
    move = ExactMove(rng)
    eta = np.asarray(p["eta"], float)
    case = _refract_per_ray(p, rng)
    directions = np.asarray(case.params["directions"], float)
    normals = np.asarray(move.vector(p["normals"]), float)
    grazing = eta == 1.0
    directions[grazing] = np.asarray(move.vector(p["directions"]), float)[grazing]
    directions[~grazing] = _unit(rng.normal(size=(int((~grazing).sum()), 3)) * 0.4 - normals[~grazing])
    return Case({"directions": np.round(directions, 12).tolist(), "normals": normals.tolist(),
                 "eta": case.params["eta"]},
                f"{int(grazing.sum())} grazing rays at η = 1 and {int((~grazing).sum())} fresh ones into glass")


def fresnel(p: dict, rng: np.random.Generator) -> Case:
    """As many cosines from grazing (0) to normal (1), another index on the same side."""
    n, out_of_glass = len(p["cos_i"]), p["eta"] > 1
    eta = num(rng.uniform(1.3, 1.8) if out_of_glass else 1 / rng.uniform(1.3, 1.8), 9)
    cos_i = np.sort(np.r_[0.0, 1.0, rng.uniform(0, 1, n - 2)])
    return Case({"cos_i": np.round(cos_i, 9).tolist(), "eta": eta}, f"{n} cosines from 0 to 1, η = {eta:.4g}")


def render(p: dict, rng: np.random.Generator) -> Case:
    """The same objects, lights moved and colours fresh, seen from a little elsewhere."""
    scene = fresh_box(p["scene"], rng)
    return Case({**p, "scene": scene}, box_description(scene))


def counters(p: dict, rng: np.random.Generator, expect: dict) -> Case:
    """As :func:`render`; between two mirrors, a fresh reflectance and cut-off (or depth), the counts computed again."""
    from autograder.whitted.public import counter_test, mirror_rays, two_mirrors
    if "reflection" not in expect or expect["reflection"] == 0:
        case = render(p, rng)
        return Case(case.params, case.describe)
    options = p["scene"]["options"]["whitted"]
    if options["max_depth"] > 5:   # the β cut-off binds, exactly at a weight (r·r·r, as the tracer multiplies)
        r, depth = num(rng.uniform(0.4, 0.7), 3), options["max_depth"]
        cut = 1.0
        for _ in range(int(rng.integers(2, 5))):
            cut *= r
    else:                          # the depth limit binds
        r, cut, depth = num(rng.uniform(0.8, 0.95), 3), options["min_weight"], int(rng.integers(2, 5))
    fresh = {**expect, "reflection": mirror_rays(r, cut, depth)}
    test = counter_test("fresh", 1, two_mirrors(r, cut, depth), p["size"], fresh)
    return Case(test.params, f"mirrors of reflectance {r:g}, cut-off {cut:g}, depth {depth}: "
                             f"{fresh['reflection']} reflection rays per pixel", test.check)


def thin_lens(p: dict, rng: np.random.Generator) -> Case:
    """A fresh camera, fresh pinhole rays inside its view, a fresh lens and plane of focus, fresh lens samples."""
    eye = np.round(rng.uniform(-6, 6, 3), 4)
    center = np.round(eye + rng.normal(size=3) * 3, 4)
    camera = {**p["camera"], "eye": eye.tolist(), "center": center.tolist(), "up": [0, 1, 0]}
    forward = (center - eye) / np.linalg.norm(center - eye)
    n = len(p["directions"])
    d = forward + rng.uniform(-0.4, 0.4, (n, 3))
    d /= np.linalg.norm(d, axis=1, keepdims=True)
    aperture, focus = round(float(rng.uniform(0.02, 0.5)), 4), round(float(rng.uniform(1, 20)), 4)
    return Case({**p, "camera": camera, "directions": np.round(d, 12).tolist(), "aperture": aperture, "focus": focus,
                 "u": np.round(rng.random((n, 2)), 12).tolist()},
                f"{n} rays of a camera at {eye.tolist()}, lens radius {aperture:g}, focused at {focus:g}")
