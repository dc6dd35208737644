"""Stage 4's fresh cases: each public test's case with new numbers of the same kind. Not shipped to students.

Graded instead of the shipped cases wherever the kit grades with its hidden tests (see
``autograder/sphere/variants.py``). Each keeps its case's purpose: max_edge 0 stays 0, a triangle
keeps its repeated corner, a hand-sized system stays hand-sized with one emitter, a patch that
shoots twice in the shipped loop shoots twice in the fresh one, six patches where the notes'
sweeps and "the current maximum" part ways still part ways, an overshot ΔB stays negative.
"""
from __future__ import annotations

import numpy as np

from cs451.grading.spec import Case, check

from autograder.fresh import Similarity, box_description, fresh_box, num
from autograder.radiosity import checks, truth as truths


def _stretch(quads: list, rng: np.random.Generator, lo: float = 0.8, hi: float = 1.25) -> tuple[np.ndarray, list]:
    factors = rng.uniform(lo, hi, 3)
    return np.asarray(quads, float) * factors, np.round(factors, 3).tolist()


def subdivide(p: dict, rng: np.random.Generator) -> Case:
    """Stretched quads (max_edge 0 keeps 0: nothing is cut), or a fresh triangle (its corner repeated) and quad."""
    quads = np.asarray(p["quads"], float)
    if len(quads) == 2 and np.allclose(quads[0][2], quads[0][3]):
        a, b = rng.uniform(2.5, 5.0, 2)
        c, d, e = rng.uniform(1.5, 3.0), rng.uniform(0.3, 1.0), rng.uniform(0.6, 1.5)
        move = Similarity(rng, shift=1.0)
        quads = [[move.point(v) for v in ([0, 0, 0], [a, 0, 0], [0, b, 0], [0, b, 0])],
                 [move.point(v) for v in ([0, 0, 1], [c, 0, 1], [c, d, 1], [0, e, 1])]]
        edge = num(rng.uniform(0.7, 1.4))
        return Case({"quads": np.round(quads, 9).tolist(), "max_edge": edge},
                    f"a {a:.3g} × {b:.3g} triangle (last corner repeated) and a quad, turned and moved, max_edge {edge:g}")
    stretched, factors = _stretch(quads, rng)
    edge = 0.0 if p["max_edge"] <= 0 else num(p["max_edge"] * rng.uniform(0.8, 1.4), 3)
    return Case({"quads": np.round(stretched, 6).tolist(), "max_edge": edge},
                f"the same {len(quads)} quads stretched by {factors} along x, y, z, max_edge {edge:g}")


def _hand_sized(rng: np.random.Generator, n: int = 3) -> dict:
    """A small reciprocal system (A_i F_ij = A_j F_ji, rows summing below 1) where only patch 0 emits."""
    areas = rng.uniform(0.5, 2.5, n)
    S = rng.uniform(0.05, 0.6, (n, n))
    S = (S + S.T) / 2
    np.fill_diagonal(S, 0)
    F = S / areas[:, None]
    F /= F.sum(axis=1).max() * rng.uniform(1.05, 1.4)
    reflectance = rng.uniform(0.1, 0.9, (n, 3))
    reflectance[0] = 0.0
    emission = np.zeros((n, 3))
    emission[0] = rng.uniform(1, 10, 3)
    return {"F": np.round(F, 6).tolist(), "areas": np.round(areas, 4).tolist(),
            "reflectance": np.round(reflectance, 3).tolist(), "emission": np.round(emission, 3).tolist()}


def shoot(p: dict, rng: np.random.Generator) -> Case:
    """Another hand-sized system; patch 0 shoots its emission, or a receiver shoots what patch 0's shot gave it."""
    system = _hand_sized(rng, len(p["areas"]))
    B = dB = system["emission"]
    if p["i"] != 0:
        B, dB = truths.shoot_by_hand(0, system["F"], system["areas"], system["reflectance"], B, dB)
    params = {"i": p["i"], **{k: system[k] for k in ("F", "areas", "reflectance")}, "radiosity": B, "unshot": dB}
    return Case(params, f"patch {p['i']} shoots in a fresh {len(p['areas'])}-patch system: F {system['F']}, "
                        f"areas {system['areas']}, emission of patch 0 {system['emission'][0]}")


def _greedy_order(s: dict, max_shots: int) -> list[int]:
    """Shots in the order of the 1988 paper: always the current maximum of ΔB·A."""
    B = dB = s["emission"]
    order = []
    for _ in range(max_shots):
        keys = [sum(abs(x) for x in row) * a for row, a in zip(dB, s["areas"])]
        i = int(np.argmax(keys))
        if keys[i] <= 0:
            break
        B, dB = truths.shoot_by_hand(i, s["F"], s["areas"], s["reflectance"], B, dB)
        order.append(i)
    return order


def _closed(p: dict) -> bool:
    """Whether a system's rows sum to 1 somewhere (a closed scene: nothing leaves it)."""
    return bool(np.isclose(np.asarray(p["F"]).sum(axis=1).max(), 1.0))


def progressive(p: dict, rng: np.random.Generator) -> Case:
    """A fresh system of as many patches with the same shots, tolerance and overshooting kind, searched until it
    shows what the shipped one shows (a patch shooting twice; the sweeps parting from the current maximum)."""
    n, shots = len(p["areas"]), p["max_shots"]
    shipped = truths.shooting_loop(p)["order"].tolist()
    overshoot = 1.0 if p["overshoot"] == 1.0 else num(rng.uniform(1.3, 1.7), 3)
    for _ in range(200):
        if n == 3:
            system = _hand_sized(rng)
        else:
            from autograder.radiosity.public import random_system
            system = random_system(n, int(rng.integers(1 << 30)), closed=_closed(p))
        params = {**system, "tolerance": p["tolerance"], "max_shots": shots, "overshoot": overshoot}
        order = truths.shooting_loop(params)["order"].tolist()
        twice = len(set(order)) < len(order)
        if twice != (len(set(shipped)) < len(shipped)):
            continue
        if n > 3 and _greedy_order(system, shots) == order:
            continue
        if p["tolerance"] > 0 and truths.stops_within_a_sweep(params) != truths.stops_within_a_sweep(p):
            continue                           # keep what the shipped case shows: a stop in the middle of a sweep
        break
    else:
        raise ValueError("no fresh system with the shipped one's property in 200 tries")
    return Case(params, f"a fresh {n}-patch system (areas {np.round(system['areas'], 3).tolist()}), at most {shots} shots, tolerance "
                        f"{p['tolerance']:g}, ω = {overshoot:g}; its shots: {order[:8]}{' …' if len(order) > 8 else ''}")


def solve_again(p: dict, rng: np.random.Generator, known: str) -> Case:
    """A fresh system of as many patches (closed if the shipped one is), with the same kind of earlier solve."""
    from autograder.radiosity.public import random_system, solve_again_case
    system = random_system(len(p["areas"]), int(rng.integers(1 << 30)), closed=_closed(p))
    overshoot = 1.0 if p["overshoot"] == 1.0 else num(rng.uniform(1.3, 1.7), 3)
    params = solve_again_case(system, known, overshoot, p["tolerance"])
    return Case(params, f"a fresh {len(p['areas'])}-patch system, rows of patches {params['known_rows']} known, "
                        f"ω = {overshoot:g}")


def furnace(p: dict, rng: np.random.Generator) -> Case:
    """The furnace with another albedo and emission; the check's closed form E/(1 − ρ) at those."""
    from autograder.radiosity.public import furnace_cube
    albedo, emission = num(rng.uniform(0.75, 0.93), 3), num(rng.uniform(0.5, 2.0), 3)
    want = truths.furnace(emission, albedo)
    params = {**furnace_cube(albedo, emission), "tolerance": p["tolerance"], "max_shots": p["max_shots"],
              "overshoot": p["overshoot"]}
    return Case(params, f"ρ = {albedo:g}, E = {emission:g} (B = E/(1 − ρ) = {want:g})",
                check(checks.furnace_uniform, want=want))


def box_scene(p: dict, rng: np.random.Generator) -> Case:
    """The same box with its light moved and recoloured and fresh colours, cut into patches of another size."""
    scene = fresh_box(p["scene"], rng)
    size = num(p["patch_size"] * rng.uniform(0.9, 1.2), 2)
    return Case({**p, "scene": scene, "patch_size": size}, f"patches of {size:g}; {box_description(scene)}")


def ambient(p: dict, rng: np.random.Generator) -> Case:
    """Fresh areas, reflectances and unshot radiosity of the same shapes; a negative ΔB stays negative."""
    n = len(p["areas"])
    signs = np.sign(np.asarray(p["unshot"], float))
    unshot = np.round(np.where(signs == 0, 0.0, signs * rng.uniform(0.1, 5.0, (n, 3))), 4)
    areas, reflectance = np.round(rng.uniform(0.5, 3.0, n), 4), np.round(rng.uniform(0.1, 0.9, (n, 3)), 3)
    return Case({"areas": areas.tolist(), "reflectance": reflectance.tolist(), "unshot": unshot.tolist()},
                f"areas {areas.tolist()}, reflectances {reflectance.tolist()}, unshot {unshot.tolist()}")


def vertex_colors(p: dict, rng: np.random.Generator, kind: str) -> Case:
    """The same polygons stretched and cut into patches of another size, with fresh radiosities."""
    if kind == "grid":
        from autograder.radiosity.public import scene_quads
        polygons, factors = _stretch(scene_quads("furnace", 3), rng)
        edge = num(rng.uniform(0.26, 0.5), 3)
    elif kind == "far":
        from autograder.radiosity.public import far_grid
        size, cuts, axis = num(rng.uniform(0.5, 4.0), 3), int(rng.integers(2, 5)), int(rng.integers(0, 3))
        offset = float(rng.choice([-1.0, 1.0]) * 2.0 ** int(rng.integers(34, 40)))
        quads, parent, radiosity = far_grid(size, cuts, offset, axis, rng)
        return Case({"quads": quads, "parent": parent, "radiosity": radiosity},
                    f"a square {size:g} wide cut {cuts} × {cuts}, {offset:g} from the origin along {'xyz'[axis]}")
    elif kind == "noisy":
        from autograder.radiosity.public import noisy_grid
        size, cuts = num(rng.uniform(100.0, 1000.0), 3), int(rng.integers(2, 5))   # copies within 1e-9 of each other
        quads, parent, radiosity = noisy_grid(size, cuts, rng)
        return Case({"quads": quads, "parent": parent, "radiosity": radiosity},
                    f"a square {size:g} wide cut {cuts} × {cuts}, shared corners apart by rounding noise")
    elif kind == "fan":
        from autograder.radiosity.public import fan_patches
        sides, radius, turn = int(rng.integers(5, 9)), num(rng.uniform(0.5, 3.0), 3), num(rng.uniform(0, 360), 1)
        patches, parent = fan_patches(sides, radius, turn)
        radiosity = np.round(rng.uniform(0.0, 2.0, (len(patches), 3)), 4)
        return Case({"quads": patches, "parent": parent, "radiosity": radiosity.tolist()},
                    f"a {sides}-gon of radius {radius:g} turned {turn:g}° and fanned from its first corner into "
                    f"{len(patches)} triangles, random radiosities")
    else:
        polygons = np.array([[[0, 0, 0], [1.5, 0, 0], [0, 1.5, 0], [0, 1.5, 0]],
                             [[1.5, 0, 0], [1.5, 1.5, 0], [0, 1.5, 0], [0, 1.5, 0]]], float)
        polygons, factors = _stretch(polygons, rng)
        edge = num(rng.uniform(0.5, 0.9), 3)
    patches, parent = truths.subdivide_by_hand(polygons, edge)
    radiosity = np.round(rng.uniform(0.0, 2.0, (len(patches), 3)), 4)
    return Case({"quads": np.round(patches, 9).tolist(), "parent": parent.tolist(), "radiosity": radiosity.tolist()},
                f"the polygons stretched by {factors} along x, y, z, cut at {edge:g} into {len(patches)} patches, "
                f"random radiosities")



def largest_first(p: dict, rng: np.random.Generator) -> Case:
    """A fresh system of as many patches, the same shots, tolerance and overshooting kind, searched until the paper's
    order parts from the notes' sweeps within its shots (the case tells the two apart)."""
    from autograder.radiosity.public import random_system
    n, shots = len(p["areas"]), p["max_shots"]
    overshoot = 1.0 if p["overshoot"] == 1.0 else num(rng.uniform(1.3, 1.7), 3)
    for _ in range(200):
        system = _hand_sized(rng) if n == 3 else random_system(n, int(rng.integers(1 << 30)), closed=_closed(p))
        params = {**system, "tolerance": p["tolerance"], "max_shots": shots, "overshoot": overshoot}
        if truths.largest_first(params)["order"].tolist() != truths.shooting_loop(params)["order"].tolist():
            return Case(params, f"a fresh system of {n} patches, overshoot {overshoot:g}, {shots} shots at most")
    raise RuntimeError("no fresh system parts the two orders")


def absorbing(p: dict, rng: np.random.Generator) -> Case:
    """A fresh system of as many patches with nothing reflecting, as many shots at most, tolerance 0."""
    from autograder.radiosity.public import absorbing as no_reflection, random_system
    system = no_reflection(random_system(len(p["areas"]), int(rng.integers(1 << 30))))
    return Case({**p, **system}, f"a fresh system of {len(p['areas'])} patches that reflects nothing")
