"""Stage 4, progressive refinement radiosity: its interface, and the scaffolding around a student's solver.

The scaffolding holds no solution. It turns a scene into polygons (stage 3's
:func:`cs451.patches.scene_polygons`), hands them to the student's subdivision
(R1), fetches rows of form factors from the trusted hemicube engine of stage 3
(:class:`cs451.formfactors.HemicubeFormFactors`, lazily, one row when a patch
shoots), runs the student's shooting loop (R2, R3), ambient term (R4) and
vertex colours (R5), and draws the Gouraud-shaded result through moderngl.

It also holds the full-matrix solvers the benchmark compares with (Jacobi,
Gauss-Seidel as in the course notes, and a direct solve of (I − ρF)B = E):
they are not student tasks.

Units: an area light of radiance L is a Lambertian emitter of radiosity
B_e = π·L; a polygon's material ``emission`` is its emitted radiosity. The
image shows radiance B/π, so it is directly comparable with a path tracer.
"""
from __future__ import annotations

import math
import sys
import time
from dataclasses import dataclass, field as dc_field
from pathlib import Path
from typing import Any, Callable, Literal

import numpy as np

from .. import schema
from ..errors import InputError, KitError
from ..scene import Scene, parse_scene
from ..schema import Context, field
from .base import Stage, Task, as_array, student_call

TASKS = (
    Task("R1", "subdivide", "Subdividing into patches", ("quads", "max_edge")),
    Task("R2", "shoot", "Shooting one patch", ("i", "row", "areas", "reflectance", "radiosity", "unshot")),
    Task("R3", "progressive_refinement", "The shooting loop",
         ("row", "areas", "reflectance", "emission", "tolerance", "max_shots", "overshoot", "on_shot")),
    Task("R4", "ambient_term", "The ambient term", ("areas", "reflectance", "unshot")),
    Task("R5", "vertex_colors", "Vertex colours", ("quads", "parent", "radiosity")),
)

SOLVERS = ("progressive", "jacobi", "gauss-seidel", "direct")
#: a patch blind from its centre (under a block resting on it) shoots from the seeing part of a 3 × 3 grid over it
RESAMPLE_BLIND = 3


@dataclass(frozen=True)
class RadiosityOptions:
    patch_size: float = field("Longest patch edge after subdivision, in scene units (0: the polygons as they are).",
                              0.0, schema.non_negative)
    tolerance: float = field("Stop when the unshot energy Σ|ΔB|·A is at most this fraction of the emitted energy ΣE·A.",
                             1e-3, schema.positive)
    max_shots: int = field("Most shots (progressive) or sweeps (Jacobi, Gauss-Seidel) before giving up; 0: 1000 per patch.",
                           0, schema.non_negative)
    ambient: bool = field("Show B + ρ·ambient, the 1988 paper's ambient term for previews (false: B alone).", True)
    overshoot: float = field("Shoot ω·ΔB and leave (1 − ω)·ΔB (1: plain progressive refinement; 1 < ω < 2 overshoots).",
                             1.0, schema.positive)
    solver: Literal["progressive", "jacobi", "gauss-seidel", "direct"] = field(
        "progressive (the student's shooting loop), or a full-matrix method for comparison.", "progressive")
    resolution: int = field("Hemicube resolution: pixels across the top face (even).", 128, schema.at_least(8))
    proximity: Literal["contour", "none"] = field(
        "Stage 3's fix for close patches: 'none' (rows of a closed scene sum to 1, so energy is conserved) or "
        "'contour' (exact point-to-polygon form factors near the shooter: more accurate single entries, but rows "
        "sum to up to 0.7% over 1, which a furnace of albedo 0.99 amplifies a hundredfold, and 3× slower).", "none")
    exposure: float = field("Multiplies the displayed radiance, before the scene's own exposure.", 1.0, schema.positive)

    def validate(self, ctx: Context) -> None:
        if not self.overshoot < 2.0:
            raise ctx.child("overshoot").error(f"must be below 2 (shooting diverges from 2 on), got {self.overshoot}")
        if not self.tolerance < 1.0:
            raise ctx.child("tolerance").error(f"must be below 1, got {self.tolerance}")


def options(scene: Scene, **overrides: Any) -> RadiosityOptions:
    """The scene's ``options.radiosity``, validated; ``overrides`` (not None) replace fields."""
    data = dict(scene.options.get("radiosity", {}))
    data.update({k: v for k, v in overrides.items() if v is not None})
    return schema.parse_record(RadiosityOptions, data, Context(scene.source or scene.name or "<scene>", "options.radiosity"))


# --- patches -------------------------------------------------------------------

@dataclass
class Patches:
    """The scene after subdivision: one row per patch."""
    quads: np.ndarray          # (m, 4, 3)
    parent: np.ndarray         # (m,) int: the polygon each patch came from
    areas: np.ndarray          # (m,)
    reflectance: np.ndarray    # (m, 3)
    emission: np.ndarray       # (m, 3) emitted radiosity
    polygons: np.ndarray       # (n, 4, 3): the polygons before subdivision
    labels: list[str] = dc_field(default_factory=list)  # per polygon: "objects[3]" or "lights[0]", for messages

    def __len__(self) -> int:
        return len(self.quads)


def scene_polygons(scene: Scene) -> tuple[np.ndarray, np.ndarray, np.ndarray, list[str]]:
    """The scene's polygons with reflectance and emitted radiosity: (quads, reflectance, emission, labels).

    Area lights become emitters of radiosity π·radiance that reflect nothing.
    """
    from ..patches import scene_polygons as polygons_of
    from ..scene import AreaLight, Polygon

    quads, names, emission = polygons_of(scene)
    labels = []
    for k, obj in enumerate(scene.objects):
        if isinstance(obj, Polygon):
            fan = len(obj.vertices) - 2 if len(obj.vertices) > 4 else 1     # polygons of 5+ corners become fans
            labels += [f"objects[{k}]"] * fan
    lights = [k for k, light in enumerate(scene.lights) if isinstance(light, AreaLight)]
    labels += [f"lights[{k}]" for k in lights]
    n_lights = len(lights)
    reflectance = np.array([scene.material(name).diffuse for name in names], dtype=np.float64).reshape(-1, 3)
    emission = np.array(emission, dtype=np.float64)
    if n_lights:
        reflectance[-n_lights:] = 0.0
        emission[-n_lights:] *= math.pi    # a Lambertian emitter of radiance L has radiosity πL
    return quads, reflectance, emission, labels


def is_closed(polygons: np.ndarray) -> bool:
    """Whether the polygons enclose space: every edge is shared by exactly two polygons (corners snapped)."""
    q = np.asarray(polygons, dtype=np.float64)
    scale = max(float(np.ptp(q.reshape(-1, 3), axis=0).max()), 1e-300)
    snapped = np.round(q / (1e-6 * scale)).astype(np.int64)
    counts: dict[tuple, int] = {}
    for poly in snapped.tolist():
        for a, b in zip(poly, poly[1:] + poly[:1]):
            if a != b:                                      # the repeated corner of a triangle is no edge
                key = (min(tuple(a), tuple(b)), max(tuple(a), tuple(b)))
                counts[key] = counts.get(key, 0) + 1
    return bool(counts) and all(c == 2 for c in counts.values())


def check_patches(p: Patches, where: str) -> None:
    """Refuse input with no solution or no meaning, with one line naming the polygon."""
    def polygon_of(patch: int) -> str:
        k = int(p.parent[patch])
        return p.labels[k] if k < len(p.labels) else f"polygon {k}"

    for name, arr in (("reflectance", p.reflectance), ("emission", p.emission), ("areas", p.areas)):
        if not np.isfinite(arr).all():
            bad = int(np.flatnonzero(~np.isfinite(arr.reshape(len(arr), -1)).all(axis=1))[0])
            raise InputError(where, polygon_of(bad), f"{name} is NaN or infinite")
    if (p.emission < 0).any():
        bad = int(np.flatnonzero((p.emission < 0).any(axis=1))[0])
        raise InputError(where, polygon_of(bad), f"negative emission {tuple(p.emission[bad])}: light cannot be absorbed by emitting")
    if (p.reflectance < 0).any() or (p.reflectance > 1).any():
        bad = int(np.flatnonzero(((p.reflectance < 0) | (p.reflectance > 1)).any(axis=1))[0])
        raise InputError(where, polygon_of(bad), f"reflectance {tuple(p.reflectance[bad])} must lie in [0, 1] (1 only where light can escape)")
    scale = float(np.ptp(p.quads.reshape(-1, 3), axis=0).max()) if len(p.quads) else 1.0
    tiny = p.areas <= 1e-12 * scale * scale
    if tiny.any():
        bad = int(np.flatnonzero(tiny)[0])
        raise InputError(where, polygon_of(bad), f"patch {bad} has zero area")
    for c, colour in enumerate("red green blue".split()):
        if np.all(p.reflectance[:, c] >= 1.0) and is_closed(p.polygons):
            raise InputError(where, "materials", f"every surface reflects all {colour} light (albedo >= 1) in a closed "
                             "scene: the light grows without bound and the radiosity equation has no solution")


def make_patches(scene: Scene, impl: Any, patch_size: float) -> Patches:
    """The scene's polygons, subdivided by the implementation's R1, with per-patch colours."""
    from ..patches import patch_areas

    quads, reflectance, emission, labels = scene_polygons(scene)
    patches, parent = call_subdivide(impl, quads, patch_size)
    p = Patches(patches, parent, patch_areas(patches), reflectance[parent], emission[parent], quads, labels)
    check_patches(p, scene.source or scene.name or "<scene>")
    return p


# --- calling the student's functions, with checks on what they return ------------

def call_subdivide(impl: Any, quads: np.ndarray, max_edge: float) -> tuple[np.ndarray, np.ndarray]:
    out = student_call(STAGE, impl, "R1", np.array(quads, dtype=np.float64), float(max_edge))
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise KitError("R1 subdivide() must return (patches, parent)")
    patches = as_array(out[0], (None, 4, 3), "R1 subdivide() patches")
    parent = as_array(out[1], (len(patches),), "R1 subdivide() parent", kind="i")
    if len(parent) and (parent.min() < 0 or parent.max() >= len(quads)):
        raise KitError(f"R1 subdivide() parent holds {int(parent.max())}, but there are {len(quads)} quads")
    return patches, parent


def call_shoot(impl: Any, i: int, row: np.ndarray, areas: np.ndarray, reflectance: np.ndarray,
          radiosity: np.ndarray, unshot: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    n = len(areas)
    out = student_call(STAGE, impl, "R2", int(i), row.copy(), areas.copy(), reflectance.copy(), radiosity.copy(), unshot.copy())
    if not isinstance(out, (tuple, list)) or len(out) != 2:
        raise KitError("R2 shoot() must return (radiosity, unshot)")
    return as_array(out[0], (n, 3), "R2 shoot() radiosity"), as_array(out[1], (n, 3), "R2 shoot() unshot")


def call_ambient(impl: Any, areas: np.ndarray, reflectance: np.ndarray, unshot: np.ndarray) -> np.ndarray:
    return as_array(student_call(STAGE, impl, "R4", areas.copy(), reflectance.copy(), unshot.copy()), (3,),
                    "R4 ambient_term()")


def call_vertex_colors(impl: Any, quads: np.ndarray, parent: np.ndarray, radiosity: np.ndarray
                  ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    out = student_call(STAGE, impl, "R5", quads.copy(), parent.copy(), radiosity.copy())
    if not isinstance(out, (tuple, list)) or len(out) != 3:
        raise KitError("R5 vertex_colors() must return (positions, colors, corners)")
    positions = as_array(out[0], (None, 3), "R5 vertex_colors() positions")
    colors = as_array(out[1], (len(positions), 3), "R5 vertex_colors() colors")
    corners = as_array(out[2], (len(quads), 4), "R5 vertex_colors() corners", kind="i")
    if corners.size and (corners.min() < 0 or corners.max() >= len(positions)):
        raise KitError(f"R5 vertex_colors() corners index vertex {int(corners.max())} of {len(positions)}")
    return positions, colors, corners


# --- solving -------------------------------------------------------------------------

class MatrixRows:
    """Rows of a given form-factor matrix, with the same interface and counters as the hemicube engine."""

    def __init__(self, matrix: np.ndarray):
        self.F = np.asarray(matrix, dtype=np.float64)
        self.counters = {"hemicubes_rendered": 0, "rows_computed": 0, "rows_cached_hits": 0}
        self._seen: set[int] = set()

    def row(self, i: int) -> np.ndarray:
        if i in self._seen:
            self.counters["rows_cached_hits"] += 1
        else:
            self._seen.add(i)
            self.counters["rows_computed"] += 1
        return self.F[i]

    def rows(self, indices: Any) -> np.ndarray:
        return np.stack([self.row(int(i)) for i in indices])

    def matrix(self) -> np.ndarray:
        return self.rows(range(len(self.F)))


def hemicube_formfactors(quads: np.ndarray, resolution: int = 128, proximity: str = "contour", ctx: Any = None,
                         batch: int = 256, seed: int = 0) -> Any:
    """Stage 3's hemicube engine over the stage-3 implementation this copy has (lazy, cached rows).

    That is the reference in the kit (see :func:`cs451.impl.earlier_stage_impl`). Pass the GL context
    you draw with as ``ctx`` when you draw while rows are still being computed (the demo): the engine
    makes its own context current for each batch and leaves it so. ``batch`` hemicubes share a
    read-back: 1 suits rows asked for one at a time (shooting), the default suits whole matrices.
    ``seed`` picks the hemicubes' random rotations (another seed: an independent estimate of F).
    """
    from ..formfactors import HemicubeFormFactors
    from ..impl import earlier_stage_impl, load_impl
    from . import hemicube as H

    impl = load_impl(earlier_stage_impl("hemicube"), "hemicube")
    return HemicubeFormFactors(quads, H.calls(impl), resolution=resolution, proximity=proximity, ctx=ctx,
                               batch=batch, seed=seed, resample_blind=RESAMPLE_BLIND)


@dataclass
class Solution:
    """A solve's result, its cost and whether it met the tolerance."""
    radiosity: np.ndarray            # (m, 3) B
    unshot: np.ndarray               # (m, 3) ΔB (zero for the full-matrix methods)
    display: np.ndarray              # (m, 3) what is drawn: B, plus ρ·ambient when asked
    method: str
    converged: bool
    residual: float                  # unshot (or residual) energy / emitted energy
    steps: int                       # shots or sweeps
    seconds: float
    order: list[int] = dc_field(default_factory=list)
    counters: dict[str, int] = dc_field(default_factory=dict)

    @property
    def message(self) -> str:
        what = "shots" if self.method == "progressive" else "sweeps" if self.method != "direct" else "solve"
        state = "converged" if self.converged else "did NOT converge (best state returned)"
        counters = ", ".join(f"{k.replace('_', ' ')} {v}" for k, v in self.counters.items())
        return (f"radiosity {self.method}: {state} after {self.steps} {what}, residual {self.residual:.3g} of the "
                f"emitted energy, {self.seconds:.2f} s" + (f"; {counters}" if counters else ""))


def energy(values: np.ndarray, areas: np.ndarray) -> float:
    """Σ_j |values_j|·A_j over all channels."""
    return float((np.abs(values).sum(axis=1) * areas).sum())


def _validate_system(areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray) -> None:
    for name, arr in (("areas", areas), ("reflectance", reflectance), ("emission", emission)):
        if not np.isfinite(arr).all():
            raise KitError(f"radiosity: {name} contains NaN or infinite values")
    if (emission < 0).any():
        raise KitError("radiosity: negative emission")
    if (areas <= 0).any():
        raise KitError(f"radiosity: patch {int(np.argmin(areas))} has zero area")
    if (reflectance < 0).any() or (reflectance > 1).any():
        raise KitError("radiosity: reflectance must lie in [0, 1]")


def solve_progressive(impl: Any, rows: Any, areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray,
                      tolerance: float = 1e-3, max_shots: int = 0, overshoot: float = 1.0, use_ambient: bool = True,
                      on_shot: Callable | None = None) -> Solution:
    """Run the implementation's shooting loop (R3) on rows from ``rows.row(i)``; counts rows and skipped patches."""
    _validate_system(areas, reflectance, emission)
    n = len(areas)
    max_shots = max_shots or 1000 * n
    fetched: list[int] = []

    def row(i: Any) -> np.ndarray:
        i = int(i)
        if not 0 <= i < n:
            raise KitError(f"R3 progressive_refinement() asked for row {i} of {n}")
        fetched.append(i)
        return np.array(rows.row(i), dtype=np.float64)

    start = time.perf_counter()
    out = student_call(STAGE, impl, "R3", row, areas.copy(), reflectance.copy(), emission.copy(),
                       float(tolerance), int(max_shots), float(overshoot), on_shot)
    seconds = time.perf_counter() - start
    if not isinstance(out, (tuple, list)) or len(out) != 3:
        raise KitError("R3 progressive_refinement() must return (radiosity, unshot, order)")
    radiosity = as_array(out[0], (n, 3), "R3 progressive_refinement() radiosity")
    unshot = as_array(out[1], (n, 3), "R3 progressive_refinement() unshot")
    order = [int(i) for i in as_array(np.asarray(list(out[2])).reshape(-1), (None,), "R3 progressive_refinement() order", kind="i")]
    emitted = energy(emission, areas)
    residual = energy(unshot, areas) / emitted if emitted > 0 else 0.0
    # with every patch reflecting all of a colour, ρ_avg = 1 and R = 1/(1 − ρ_avg) is infinite: show B alone
    ambient_defined = not np.all(reflectance >= 1.0, axis=0).any()
    display = (radiosity + reflectance * call_ambient(impl, areas, reflectance, unshot)
               if use_ambient and ambient_defined else radiosity)
    counters = dict(getattr(rows, "counters", {}))
    counters.update(patches=n, shots=len(order), distinct_shooters=len(set(order)), rows_requested=len(fetched),
                    patches_never_shot=n - len(set(order)),
                    zero_albedo_receivers=int((reflectance.max(axis=1) == 0).sum()))
    return Solution(radiosity, unshot, display, "progressive", residual <= tolerance * (1 + 1e-9), residual,
                    len(order), seconds, order, counters)


def shooting_matrix(F: np.ndarray, areas: np.ndarray) -> np.ndarray:
    """The form factors shooting uses: F̃_ji = F_ij·A_i/A_j, from the shooters' rows.

    Progressive refinement takes row i (from patch i's hemicube) and spreads patch i's energy
    with it; the gathering form B_j = E_j + ρ_j Σ_i F_ji B_i would take column entries from the
    receivers' hemicubes instead. With exact reciprocity (A_i F_ij = A_j F_ji) the two are equal;
    hemicube rows are not exactly reciprocal (a small bright light covers few cells of a distant
    receiver's hemicube), so the full-matrix solvers are run on F̃ to solve the same equations.
    """
    F = np.asarray(F, dtype=np.float64)
    return (F * areas[:, None] / areas[None, :]).T


def system_matrix(F: np.ndarray, reflectance: np.ndarray, channel: int) -> np.ndarray:
    """I − diag(ρ_c)·F for one colour channel."""
    return np.eye(len(F)) - reflectance[:, channel:channel + 1] * F


def residual_energy(F: np.ndarray, areas: np.ndarray, reflectance: np.ndarray, emission: np.ndarray,
                    B: np.ndarray) -> float:
    """Σ|E + ρFB − B|·A over all channels: how far B is from solving the radiosity equation (in energy)."""
    return energy(emission + reflectance * (F @ B) - B, areas)


def solve_direct(F: np.ndarray, reflectance: np.ndarray, emission: np.ndarray) -> np.ndarray:
    """B from (I − ρF)B = E, one dense LU solve per channel; a clear error when the system is singular."""
    B = np.empty_like(np.asarray(emission, dtype=np.float64))
    for c in range(3):
        M = system_matrix(F, reflectance, c)
        try:
            B[:, c] = np.linalg.solve(M, emission[:, c])
        except np.linalg.LinAlgError:
            raise KitError("radiosity: (I − ρF) is singular (an albedo of 1 in a closed scene?): no solution") from None
        if np.linalg.cond(M, 1) > 1e14:
            raise KitError("radiosity: (I − ρF) is numerically singular (an albedo of 1 in a closed scene?): no solution")
    return B


def solve_iterative(method: Literal["jacobi", "gauss-seidel"], F: np.ndarray, areas: np.ndarray, reflectance: np.ndarray,
                    emission: np.ndarray, tolerance: float = 1e-3, max_sweeps: int = 0,
                    on_sweep: Callable[[int, np.ndarray], None] | None = None) -> Solution:
    """Jacobi (B ← E + ρFB, all at once) or Gauss-Seidel (patch by patch, using the newest values), on the full matrix.

    Stops when the residual energy Σ|E + ρFB − B|·A is at most ``tolerance`` of the emitted energy.
    """
    _validate_system(areas, reflectance, emission)
    n = len(areas)
    max_sweeps = max_sweeps or 10_000
    F = np.asarray(F, dtype=np.float64)
    B = np.array(emission, dtype=np.float64)
    emitted = energy(emission, areas)
    start = time.perf_counter()
    sweeps, residual = 0, residual_energy(F, areas, reflectance, emission, B) / max(emitted, 1e-300)
    K = reflectance[:, None, :] * F[:, :, None]                      # (n, n, 3): ρ_i F_ij
    while residual > tolerance and sweeps < max_sweeps:
        if method == "jacobi":
            B = emission + np.einsum("ijc,jc->ic", K, B)
        else:  # Gauss-Seidel as in the notes: B_i = (E_i + ρ_i Σ_{j≠i} F_ij B_j) / (1 − ρ_i F_ii), in place
            for i in range(n):
                B[i] = (emission[i] + (K[i] * B).sum(axis=0) - K[i, i] * B[i]) / (1.0 - K[i, i])
        sweeps += 1
        residual = residual_energy(F, areas, reflectance, emission, B) / max(emitted, 1e-300)
        if on_sweep is not None:
            on_sweep(sweeps, B)
    seconds = time.perf_counter() - start
    return Solution(B, np.zeros_like(B), B, method, residual <= tolerance, residual, sweeps, seconds)


def solve(patches: Patches, impl: Any, opts: RadiosityOptions, rows: Any = None,
          on_shot: Callable | None = None) -> Solution:
    """Solve a scene's patches with the chosen solver; rows from the hemicube engine unless given."""
    if rows is None:
        rows = hemicube_formfactors(patches.quads, opts.resolution, opts.proximity,
                                    batch=1 if opts.solver == "progressive" else 256)
    a, rho, E = patches.areas, patches.reflectance, patches.emission
    if opts.solver == "progressive":
        return solve_progressive(impl, rows, a, rho, E, opts.tolerance, opts.max_shots, opts.overshoot, opts.ambient, on_shot)
    F = shooting_matrix(rows.matrix(), a)
    if opts.solver == "direct":
        start = time.perf_counter()
        B = solve_direct(F, rho, E)
        residual = residual_energy(F, a, rho, E, B) / max(energy(E, a), 1e-300)
        return Solution(B, np.zeros_like(B), B, "direct", True, residual, 1, time.perf_counter() - start,
                        counters=dict(getattr(rows, "counters", {})))
    sol = solve_iterative(opts.solver, F, a, rho, E, opts.tolerance, opts.max_shots)  # type: ignore[arg-type]
    sol.counters = dict(getattr(rows, "counters", {}))
    return sol


# --- display ---------------------------------------------------------------------------

VERTEX_SHADER = """#version 330
uniform mat4 u_mvp;
in vec3 in_position;
in vec3 in_color;
out vec3 v_color;
void main() { gl_Position = u_mvp * vec4(in_position, 1.0); v_color = in_color; }
"""
FRAGMENT_SHADER = """#version 330
in vec3 v_color;
out vec4 frag_color;
void main() { frag_color = vec4(v_color, 1.0); }
"""


def camera_view(scene: Scene) -> np.ndarray:
    """World to eye for the scene camera, from the stage-3 implementation's H2 (see :mod:`cs451.viewing`)."""
    from ..impl import earlier_stage_impl, load_impl
    from ..viewing import camera_view as view_from
    from . import hemicube as H

    impl = load_impl(earlier_stage_impl("hemicube"), "hemicube")
    return view_from(scene.camera, lambda c, n, u: H.call_views(impl, c, n, u))


def camera_matrix(scene: Scene, width: int, height: int, view: np.ndarray | None = None) -> np.ndarray:
    """Projection · view of the scene camera: pyrender's projection, the view given or from :func:`camera_view`."""
    from ..viewing import camera_projection

    return camera_projection(scene.camera, width, height) @ (camera_view(scene) if view is None else view)


class GouraudDrawer:
    """Draws coloured quads with colours interpolated across them, into a float framebuffer."""

    def __init__(self, ctx: Any = None):
        from ..gl import create_context

        self.ctx = ctx or create_context()
        self.program = self.ctx.program(vertex_shader=VERTEX_SHADER, fragment_shader=FRAGMENT_SHADER)

    def draw(self, positions: np.ndarray, colors: np.ndarray, corners: np.ndarray, mvp: np.ndarray,
             width: int, height: int, background: Any = (0.0, 0.0, 0.0), fbo: Any = None,
             viewport: tuple[int, int, int, int] | None = None) -> np.ndarray | None:
        """Draw into ``fbo`` (a window's screen, at ``viewport``: nothing is read back) or a new float framebuffer (returned)."""
        ctx = self.ctx
        read = fbo is None
        if read:
            fbo = ctx.framebuffer(color_attachments=[ctx.renderbuffer((width, height), 4, dtype="f4")],
                                  depth_attachment=ctx.depth_renderbuffer((width, height)))
        fbo.use()
        viewport = viewport or (0, 0, width, height)
        ctx.viewport = viewport
        ctx.enable(ctx.DEPTH_TEST)
        ctx.disable(ctx.CULL_FACE)                   # both sides of a patch show its radiosity
        fbo.clear(*background, 1.0, depth=1.0, viewport=viewport)
        triangles = np.concatenate([corners[:, [0, 1, 2]], corners[:, [0, 2, 3]]]).astype("i4")
        vbo = ctx.buffer(np.hstack([positions, colors]).astype("f4").tobytes())
        ibo = ctx.buffer(triangles.tobytes())
        vao = ctx.vertex_array(self.program, [(vbo, "3f 3f", "in_position", "in_color")], ibo)
        self.program["u_mvp"].write(np.asarray(mvp, dtype="f4").T.tobytes())
        vao.render()
        ctx.finish()
        for obj in (vao, ibo, vbo):
            obj.release()
        if not read:
            return None
        data = np.frombuffer(fbo.read(components=3, dtype="f4"), dtype=np.float32).reshape(height, width, 3)
        fbo.release()
        return np.flipud(data).astype(np.float64)


def draw_solution(scene: Scene, impl: Any, patches: Patches, display: np.ndarray, size: tuple[int, int] | None,
                  exposure: float = 1.0, drawer: GouraudDrawer | None = None, view: np.ndarray | None = None) -> np.ndarray:
    """The Gouraud-shaded image of per-patch radiosities (shown as radiance B/π), through the student's R5."""
    width, height = size or (scene.image.width, scene.image.height)
    positions, colors, corners = call_vertex_colors(impl, patches.quads, patches.parent, display)
    drawer = drawer or GouraudDrawer()
    return drawer.draw(positions, colors * (exposure / math.pi), corners, camera_matrix(scene, width, height, view),
                       width, height, scene.image.background)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, verbose: bool = True, **overrides: Any) -> np.ndarray:
    """Subdivide, solve and draw a scene with an implementation; returns linear radiance (h, w, 3)."""
    opts = options(scene, **overrides)
    patches = make_patches(scene, impl, opts.patch_size)
    sol = solve(patches, impl, opts)
    if verbose:
        print(("" if sol.converged else "warning: ") + sol.message, file=sys.stderr)
    return draw_solution(scene, impl, patches, sol.display, size, opts.exposure)


# --- probes: what the autograder's worker asks a submission for -----------------------

def probe_subdivide(impl: Any, quads: list, max_edge: float) -> dict[str, np.ndarray]:
    patches, parent = call_subdivide(impl, np.asarray(quads, dtype=np.float64), max_edge)
    return {"patches": patches, "parent": parent}


def probe_shoot(impl: Any, i: int, F: list, areas: list, reflectance: list, radiosity: list, unshot: list
                ) -> dict[str, np.ndarray]:
    F_ = np.asarray(F, dtype=np.float64)
    B, dB = call_shoot(impl, i, F_[i], np.asarray(areas, float), np.asarray(reflectance, float),
                  np.asarray(radiosity, float), np.asarray(unshot, float))
    return {"radiosity": B, "unshot": dB}


def _system(params: dict, given: dict) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    if "F" in given:
        return (given["F"], given["areas"], given["reflectance"], given["emission"])
    return tuple(np.asarray(params[k], dtype=np.float64) for k in ("F", "areas", "reflectance", "emission"))  # type: ignore[return-value]


def probe_progressive(impl: Any, tolerance: float, max_shots: int, overshoot: float = 1.0, scene: dict | None = None,
                      patch_size: float = 0.0, resolution: int = 64, F: list | None = None, areas: list | None = None,
                      reflectance: list | None = None, emission: list | None = None, **given: np.ndarray
                      ) -> dict[str, np.ndarray]:
    """The shooting loop on a given system (small hand-worked scenes in the parameters, or a scene's trusted arrays)."""
    F_, a, rho, E = _system({"F": F, "areas": areas, "reflectance": reflectance, "emission": emission}, given)
    rows = MatrixRows(F_)
    sol = solve_progressive(impl, rows, a, rho, E, tolerance, max_shots, overshoot, use_ambient=False)
    return {"radiosity": sol.radiosity, "unshot": sol.unshot, "order": np.asarray(sol.order, dtype=np.int64),
            "rows_computed": np.asarray(rows.counters["rows_computed"]),
            "direct": solve_direct(shooting_matrix(F_, a), rho, E),
            "areas": a, "emission": E, "reflectance": rho}


def probe_ambient(impl: Any, areas: list, reflectance: list, unshot: list) -> dict[str, np.ndarray]:
    return {"ambient": call_ambient(impl, np.asarray(areas, float), np.asarray(reflectance, float), np.asarray(unshot, float))}


def probe_vertex_colors(impl: Any, quads: list, parent: list, radiosity: list) -> dict[str, np.ndarray]:
    positions, colors, corners = call_vertex_colors(impl, np.asarray(quads, float), np.asarray(parent, dtype=np.int64),
                                               np.asarray(radiosity, float))
    return {"positions": positions, "colors": colors, "corners": corners}


def probe_system(impl: Any, scene: dict, patch_size: float = 0.0, resolution: int = 64, **_: Any) -> dict[str, np.ndarray]:
    """Trusted inputs for the scene tests (run on the reference only): patches, colours, the full F and the camera view."""
    sc = parse_scene(scene, "<probe scene>")
    p = make_patches(sc, impl, patch_size)
    F = hemicube_formfactors(p.quads, resolution).matrix()
    return {"quads": p.quads, "parent": p.parent, "areas": p.areas, "reflectance": p.reflectance,
            "emission": p.emission, "F": np.asarray(F, dtype=np.float64), "view": camera_view(sc)}


def probe_solved_system(impl: Any, scene: dict, size: list[int] | None = None, tolerance: float = 1e-3,
                        use_ambient: bool = True, max_shots: int = 0, patch_size: float = 0.0, resolution: int = 64
                        ) -> dict[str, np.ndarray]:
    """Trusted inputs for R5's image tests (run on the reference only): the system, and the per-patch values
    the reference's R3 and R4 display on it, so that an image test judges R5 alone."""
    out = probe_system(impl, scene, patch_size, resolution)
    sol = solve_progressive(impl, MatrixRows(out["F"]), out["areas"], out["reflectance"], out["emission"], tolerance,
                            max_shots, 1.0, use_ambient)
    out["display"] = sol.display
    return out


def probe_render(impl: Any, scene: dict, size: list[int], tolerance: float = 1e-3, use_ambient: bool = True,
                 max_shots: int = 0, patch_size: float = 0.0, resolution: int = 64, **given: np.ndarray
                 ) -> dict[str, np.ndarray]:
    """Draw ``scene`` on the trusted patches and form factors (``given``) with the submission's R5.

    The per-patch values shown come from ``given["display"]`` when the test gives them (the reference's
    R3 and R4), else from the submission's own R3 and R4.
    """
    sc = parse_scene(scene, "<probe scene>")
    quads, parent = given["quads"], given["parent"]
    p = Patches(quads, parent, given["areas"], given["reflectance"], given["emission"], quads)
    if "display" in given:
        display = given["display"]
    else:
        display = solve_progressive(impl, MatrixRows(given["F"]), p.areas, p.reflectance, p.emission, tolerance,
                                    max_shots, 1.0, use_ambient).display
    image = draw_solution(sc, impl, p, display, (int(size[0]), int(size[1])), options(sc).exposure,
                          view=given.get("view"))
    return {"image": np.clip(image * sc.image.exposure, 0.0, 1.0), "display": display}


# --- the lecture demo: the solution building up shot by shot ---------------------------------

def demo_shots(total_hint: int, frames: int | None) -> list[int]:
    """Shots after which to show a frame: 0, 1, 2, 4, 8, … (the picture changes fastest early on)."""
    shots = [0] + [2 ** k for k in range(0, 40) if 2 ** k <= max(total_hint, 1)]
    return shots[:frames] if frames else shots


def _demo(module: Any, output: Path, window: bool, frames: int | None, scene_name: str = "cornell-box",
          size: tuple[int, int] = (256, 256)) -> list[Path]:
    """Headless: frames (B alone | B + ρ·ambient) after 0, 1, 2, 4, … shots, as PNGs and one animated GIF.

    With a window: the same two panels, redrawn as the shots go by.
    """
    from ..imageio import to_uint8
    from ..scene import load_scene

    scene = load_scene(scene_name)
    opts = options(scene)
    patches = make_patches(scene, module, opts.patch_size)
    wanted = set(demo_shots(50 * len(patches), frames))
    width, height = size
    mvp = camera_matrix(scene, width, height)
    a, rho = patches.areas, patches.reflectance
    gl_window = _DemoWindow(2 * width, height) if window else None
    drawer = GouraudDrawer(gl_window.ctx if gl_window else None)
    rows = hemicube_formfactors(patches.quads, opts.resolution, opts.proximity, ctx=drawer.ctx, batch=1)
    pictures: list[np.ndarray] = []

    def panels(B: np.ndarray, dB: np.ndarray) -> list[np.ndarray]:
        shown = [B, B + rho * call_ambient(module, a, rho, dB)]
        out = []
        for k, values in enumerate(shown):
            positions, colors, corners = call_vertex_colors(module, patches.quads, patches.parent, values)
            scaled = colors * (opts.exposure / math.pi)
            if gl_window is not None:
                drawer.draw(positions, scaled, corners, mvp, width, height, scene.image.background, gl_window.ctx.screen,
                            viewport=(k * width, 0, width, height))
            else:
                out.append(drawer.draw(positions, scaled, corners, mvp, width, height, scene.image.background))
        return out

    def on_shot(shots: int, i: int, B: np.ndarray, dB: np.ndarray) -> None:
        if shots not in wanted:
            return
        if gl_window is None:
            pictures.append(np.hstack(panels(B, dB)))
            return
        gl_window.show(lambda: panels(B, dB))
        if gl_window.closed or (frames and gl_window.frames >= frames):
            raise _StopDemo

    try:
        on_shot(0, -1, patches.emission.copy(), patches.emission.copy())
        sol = solve_progressive(module, rows, a, rho, patches.emission, opts.tolerance, opts.max_shots, opts.overshoot,
                                True, on_shot)
        if gl_window is None:
            pictures.append(np.hstack(panels(sol.radiosity, sol.unshot)))
        else:                                       # the answer stays up until the window is closed
            while not gl_window.closed and not (frames and gl_window.frames >= frames):
                gl_window.show(lambda: panels(sol.radiosity, sol.unshot))
    except _StopDemo:
        pass
    finally:
        if gl_window is not None:
            gl_window.close()
    if gl_window is not None:
        return []
    return _write_animation(output, [to_uint8(p, scene.image.exposure, scene.image.srgb) for p in pictures])


class _StopDemo(Exception):
    """The window was closed."""


class _DemoWindow:
    """A GLFW window for the demo (q or Escape closes it)."""

    def __init__(self, width: int, height: int):
        try:
            import glfw
            import moderngl
        except ImportError as err:
            raise KitError(f"the demo window needs glfw ({err}); run ./setup.sh") from None
        if not glfw.init():
            raise KitError("cannot open a window (glfw.init failed): is DISPLAY set? Use --no-window for images")
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        self.glfw = glfw
        self.win = glfw.create_window(width, height, "cs451 radiosity: B | B + ambient (q quits)", None, None)
        if not self.win:
            glfw.terminate()
            raise KitError("cannot open a window (glfw.create_window failed); use --no-window for images")
        glfw.make_context_current(self.win)
        self.ctx = moderngl.create_context()
        glfw.set_key_callback(self.win, self._key)
        self.closed = False
        self.frames = 0

    def _key(self, win: Any, key: int, _scancode: int, action: int, _mods: int) -> None:
        if action == self.glfw.PRESS and key in (self.glfw.KEY_Q, self.glfw.KEY_ESCAPE):
            self.closed = True

    def show(self, draw: Callable[[], Any]) -> None:
        draw()
        self.glfw.swap_buffers(self.win)
        self.glfw.poll_events()
        self.frames += 1
        self.closed = self.closed or bool(self.glfw.window_should_close(self.win))

    def close(self) -> None:
        self.glfw.terminate()


def _write_animation(folder: Path, frames: list[np.ndarray]) -> list[Path]:
    from PIL import Image as PILImage

    folder.mkdir(parents=True, exist_ok=True)
    paths = []
    for k, frame in enumerate(frames):
        path = folder / f"radiosity-{k:02d}.png"
        PILImage.fromarray(frame).save(path)
        paths.append(path)
    gif = folder / "radiosity.gif"
    images = [PILImage.fromarray(f) for f in frames]
    durations = [400] * (len(images) - 1) + [2000]
    images[0].save(gif, save_all=True, append_images=images[1:], duration=durations, loop=0)
    return [gif, *paths]


STAGE = Stage(
    name="radiosity", number=4, title="Progressive refinement radiosity", handout="04-radiosity", tasks=TASKS,
    render=render,
    probes={"subdivide": probe_subdivide, "shoot": probe_shoot, "progressive": probe_progressive,
            "ambient": probe_ambient, "vertex_colors": probe_vertex_colors, "system": probe_system,
            "solved_system": probe_solved_system, "render": probe_render},
    demo=_demo,
    builds_on=("hemicube",),
)

