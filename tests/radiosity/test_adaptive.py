"""Adaptive subdivision within substructuring (cs451/stages/radiosity/bench_adaptive*.py, notes §2.3).

Truths: a floor lit by a small light past a square plate, whose hard shadow edge is known in closed form
(the plate projected from the light's centre, where a patch shoots from) and whose direct light is the
point-source formula; the white furnace (energy: mean B = E/(1 − ρs)); a plain substructured solve on
the refined elements (the re-gather must give what those elements would have received).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from cs451.stages.radiosity import bench_adaptive as AD
from cs451.stages.radiosity import bench_adaptive_display as ADD
from cs451.stages.radiosity import bench_adaptive_runs as ADR
from cs451.stages.radiosity import bench_substructuring as S
from bench.meshes import subdivide_uniform
from cs451.errors import KitError
from cs451.formfactors import HemicubeFormFactors
from cs451.gl import create_context
from cs451.impl import load_impl, resolve_impl
from cs451.patches import patch_areas, patch_centers
from cs451.patching import Patches
from cs451.scene import load_scene
from cs451.stages import radiosity as R
from cs451.stages.hemicube import calls
from cs451 import patching as P

REF = load_impl(resolve_impl("reference", "radiosity"), "radiosity")
HEMICUBE = load_impl(resolve_impl("reference", "hemicube"), "hemicube")

# a 4 × 4 floor (y = 0, facing up), a 0.8 × 0.8 plate at y = 0.5 facing it, a 0.1 × 0.1 light at y = 1.5 facing down
FLOOR = [[4, 0, 0], [0, 0, 0], [0, 0, 4], [4, 0, 4]]
PLATE = [[2.4, .5, 1.6], [2.4, .5, 2.4], [1.6, .5, 2.4], [1.6, .5, 1.6]]
LIGHT = [[2.05, 1.5, 1.95], [2.05, 1.5, 2.05], [1.95, 1.5, 2.05], [1.95, 1.5, 1.95]]
CENTRE, HEIGHT, PLATE_HALF, PLATE_Y, RHO, EMIT = np.array([2.0, 1.5, 2.0]), 1.5, 0.4, 0.5, 0.5, 100.0
SHADOW_HALF = PLATE_HALF * HEIGHT / (HEIGHT - PLATE_Y)        # the plate's shadow from the light's centre: 0.6
RESOLUTION = 256                                              # the light's hemicube must resolve 1/32-wide elements
LIGHT_PATCH = 65                                              # 64 floor patches, the plate, the light


@pytest.fixture(scope="module")
def ctx():
    return create_context()


def engine_for(ctx, resolution=RESOLUTION):
    return lambda quads: HemicubeFormFactors(quads, calls(HEMICUBE), resolution=resolution, proximity="none", ctx=ctx)


def shadow_patches() -> Patches:
    polygons = np.array([FLOOR, PLATE, LIGHT], dtype=np.float64)
    floor, _ = subdivide_uniform(polygons[:1], 8)                # 64 patches of 0.5 × 0.5
    quads = np.concatenate([floor, polygons[1:]])
    polygon = np.array([0] * 64 + [1, 2])
    rho = np.where(polygon[:, None] == 2, 0.0, RHO) * np.ones(3)
    emission = np.where(polygon[:, None] == 2, EMIT, 0.0) * np.ones(3)
    return Patches(quads, polygon, patch_areas(quads), rho, emission, polygons)


def edge_distance(points: np.ndarray) -> np.ndarray:
    """Distance on the floor from each point to the analytic shadow's outline (a square of half-side 0.6)."""
    dx, dz = np.abs(points[:, 0] - CENTRE[0]), np.abs(points[:, 2] - CENTRE[2])
    outside = np.hypot(np.maximum(dx - SHADOW_HALF, 0), np.maximum(dz - SHADOW_HALF, 0))
    inside = (dx <= SHADOW_HALF) & (dz <= SHADOW_HALF)
    return np.where(inside, SHADOW_HALF - np.maximum(dx, dz), outside)


def direct_light(points: np.ndarray, shot: float) -> np.ndarray:
    """B on the floor from the light shooting ``shot`` from its centre: ρ·S·A_L·cos θ_L·cos θ / (π r²), zero in the shadow."""
    d = CENTRE - points
    r2 = (d ** 2).sum(axis=1)
    crossing = points + ((PLATE_Y - points[:, 1]) / d[:, 1])[:, None] * d
    blocked = (np.abs(crossing[:, 0] - CENTRE[0]) <= PLATE_HALF) & (np.abs(crossing[:, 2] - CENTRE[2]) <= PLATE_HALF)
    return np.where(blocked, 0.0, RHO * shot * 0.01 * HEIGHT ** 2 / (math.pi * r2 ** 2))


def displayed_floor_error(sol: AD.AdaptiveSolution) -> float:
    """Relative L1 error of the floor as drawn (R5's colours, T-vertices anchored; each element's triangles (0,1,2),
    (0,2,3) interpolated linearly, as the rasteriser does on these flat squares) against :func:`direct_light`."""
    colors = ADD.display_colors(sol, lambda q, p, b: R.call_vertex_colors(REF, q, p, b), 66, watertight=False)
    _, col, corners = colors(sol.mesh.quads, sol.polygon, sol.radiosity)
    floor = np.flatnonzero(sol.polygon == 0)
    s = (np.arange(8) + 0.5) / 8
    u, v = (g.ravel()[None, :, None] for g in np.meshgrid(s, s, indexing="ij"))
    a, b, c, d = (sol.mesh.quads[floor][:, i][:, None, :] for i in range(4))
    points = (1 - u) * (1 - v) * a + u * (1 - v) * b + u * v * c + (1 - u) * v * d
    c0, c1, c2, c3 = (col[corners[floor]][:, i, :1][:, None, :] for i in range(4))
    shown = np.where(u >= v, c0 + u * (c1 - c0) + v * (c2 - c1), c0 + v * (c3 - c0) + u * (c2 - c3))[..., 0]
    truth = direct_light(points.reshape(-1, 3), float(sol.shot[LIGHT_PATCH, 0])).reshape(len(floor), -1)
    area = sol.mesh.areas[floor][:, None]
    return float((area * np.abs(shown - truth)).sum() / (area * truth).sum())


@pytest.fixture(scope="module")
def shadow(ctx):
    """The shadow scene's direct light (the light's one shot): uniform 4 × 4 elements per patch, adaptive at that count."""
    patches = shadow_patches()
    engine = engine_for(ctx)
    uniform = AD.uniform_solution(patches, engine, 4, tolerance=0.99)
    adaptive = AD.solve_adaptive(patches, engine, k=1, threshold=0.3, max_depth=4, converged_passes=0, tolerance=0.99,
                                 budget=len(uniform.mesh))
    free = AD.solve_adaptive(patches, engine, k=1, threshold=0.3, max_depth=4, converged_passes=0, tolerance=0.99)
    return patches, engine, uniform, adaptive, free


def test01_refined_elements_lie_along_the_analytic_shadow_edge(shadow):
    patches, _, _, _, free = shadow
    assert free.shots == 1 and free.converged                     # the light alone: the direct light
    floor = free.polygon == 0
    centres = patch_centers(free.mesh.quads)
    finest = floor & (free.mesh.depth == 4)                       # 1/32 wide
    assert finest.sum() >= 200
    near = edge_distance(centres[finest]) <= 0.1
    # the band within 0.1 of the edge is 6% of the floor: elements strewn at random would fall in it as often
    band = 4 * 2 * SHADOW_HALF * 2 * 0.1 / 16
    assert band < 0.07 and near.mean() >= 0.95, f"{near.mean():.2f} of the finest elements within 0.1 of the edge"
    # the first pass splits most patches (across 0.5 the light falls off by more than 30% too); from the second
    # level on, every element lies within two of its parents' widths of the edge
    assert (floor & (free.mesh.depth >= 1)).sum() > 0.75 * 4 * 64 - 3 * finest.sum()
    for depth in range(2, 5):
        level = floor & (free.mesh.depth == depth)
        assert edge_distance(centres[level]).max() <= 2 * 0.5 / 2 ** (depth - 1), depth
    # and the plate and light, uniform in their light, stay whole
    assert (free.mesh.depth[free.polygon != 0] == 0).all()


def test02_refinement_stops_at_max_depth(ctx):
    patches = shadow_patches()
    engine = engine_for(ctx, 64)
    for depth in (0, 1, 2):
        sol = AD.solve_adaptive(patches, engine, k=1, threshold=0.3, max_depth=depth, converged_passes=0, tolerance=0.99)
        assert sol.mesh.depth.max() == depth and sol.mesh.cells == 2 ** depth
        assert (sol.mesh.box[:, 2] - sol.mesh.box[:, 0]).min() == 1   # the finest element is one lattice cell
        pairs = AD.neighbour_pairs(sol.mesh, sol.sides, len(patches))
        lit = patches.emission[sol.mesh.patch].max(axis=1) == 0
        # elements over the threshold remain at the deepest level: the depth stopped the refinement, not the criterion
        over = AD.select(sol.mesh, pairs, sol.radiosity, lit, 0.3, max_depth=99)
        assert (sol.mesh.depth[over] == depth).any()
        assert not (sol.mesh.depth[AD.select(sol.mesh, pairs, sol.radiosity, lit, 0.3, max_depth=depth)] >= depth).any()
    with pytest.raises(KitError, match="max_depth"):
        AD.split(sol.mesh, [int(np.argmax(sol.mesh.depth))])
    with pytest.raises(KitError, match="below the"):
        AD.solve_adaptive(patches, engine, k=2, budget=10)


def test03_elements_tile_their_patches(shadow):
    patches, _, _, adaptive, free = shadow
    for sol in (adaptive, free):
        areas = np.bincount(sol.mesh.patch, weights=sol.mesh.areas, minlength=len(patches))
        assert np.allclose(areas, patches.areas, rtol=1e-12, atol=0)
        box = sol.mesh.box
        cells = np.bincount(sol.mesh.patch, weights=(box[:, 2] - box[:, 0]) * (box[:, 3] - box[:, 1]))
        assert (cells == sol.mesh.cells ** 2).all()
        # the corners are the patch's bilinear map at the box corners, so neighbours share them exactly
        q = patches.quads[sol.mesh.patch]
        u, v = box[:, [0, 2, 2, 0]] / sol.mesh.cells, box[:, [1, 1, 3, 3]] / sol.mesh.cells
        u, v = u[..., None], v[..., None]
        want = (1 - u) * (1 - v) * q[:, [0]] + u * (1 - v) * q[:, [1]] + u * v * q[:, [2]] + (1 - u) * v * q[:, [3]]
        assert np.abs(sol.mesh.quads - want).max() < 1e-12


def test04_white_furnace_stays_at_the_closed_form_through_refinement(ctx):
    quads, _, _, _ = P.radiosity_surfaces(load_scene("furnace"))
    patch_quads, _ = subdivide_uniform(quads, 2)
    n, rho = len(patch_quads), 0.9
    patches = Patches(patch_quads, np.repeat(np.arange(6), 4), patch_areas(patch_quads), np.full((n, 3), rho),
                      np.ones((n, 3)), quads)
    # threshold 0: every contrast the hemicube's noise makes is refined, so the elements change at every pass
    sol = AD.solve_adaptive(patches, engine_for(ctx, 32), k=1, threshold=0.0, max_depth=2, budget=4 * n * 3,
                            tolerance=1e-6)
    assert sol.converged and sum(p["splits"] for p in sol.passes) > n
    assert sol.mesh.depth.max() == 2
    a = sol.mesh.areas
    rows = ADD.ElementRows(engine_for(ctx, 32), patch_quads, sol.mesh, sol.sides, patches.parent)
    s = rows.row(0).sum()                                         # the delta form factors' total (1.0005 at 32)
    assert np.allclose(rows.rows(range(n)).sum(axis=1), s, rtol=1e-12)   # watertight: every hemicube sees it all
    mean = (sol.radiosity[:, 0] * a).sum() / a.sum()
    assert abs(mean * (1 - rho * s) - 1) < 1e-5


def test05_the_regather_is_what_the_refined_elements_would_have_received(shadow):
    """Solving again from scratch on the final elements gives the adaptive answer: the re-gather loses nothing."""
    patches, engine, _, adaptive, _ = shadow
    mesh = adaptive.mesh
    rows = ADD.ElementRows(engine, patches.quads, mesh, adaptive.sides, patches.parent)
    again = S.solve_substructured(rows, mesh.patch, mesh.areas, patches.reflectance[mesh.patch],
                                  patches.emission[mesh.patch], tolerance=0.99)
    assert again.shots == adaptive.shots == 1
    assert np.allclose(again.radiosity, adaptive.radiosity, rtol=1e-9, atol=1e-12)
    # continuing a solve needs both arrays
    with pytest.raises(KitError, match="both"):
        S.solve_substructured(rows, mesh.patch, mesh.areas, patches.reflectance[mesh.patch],
                              patches.emission[mesh.patch], radiosity=adaptive.radiosity)


def test06_adaptive_beats_uniform_at_equal_element_count(shadow):
    _, _, uniform, adaptive, _ = shadow
    assert 0.95 * len(uniform.mesh) <= len(adaptive.mesh) <= len(uniform.mesh)
    e_uniform, e_adaptive = displayed_floor_error(uniform), displayed_floor_error(adaptive)
    # measured: 0.068 uniform, 0.042 adaptive
    assert e_adaptive < 0.75 * e_uniform, (e_uniform, e_adaptive)


def test07_t_vertices_are_found_across_patches_and_anchored():
    # one polygon of two patches side by side; patch 0 split once, then its child at the shared side again
    polygon = np.array([[0, 0, 0], [2, 0, 0], [2, 0, 1], [0, 0, 1]], dtype=np.float64)[None]
    quads, _ = subdivide_uniform(polygon, 1)
    patches = np.concatenate([quads * [0.5, 1, 1], quads * [0.5, 1, 1] + [1, 0, 0]])      # x in [0, 1] and [1, 2]
    parent = np.zeros(2, dtype=np.int64)
    sides = AD.shared_sides(patches, parent)
    assert sides.tolist() == [[0, 1, 1, 3], [1, 3, 0, 1]]        # patch 0's side 1 is patch 1's side 3, run the other way
    mesh = AD.initial_mesh(patches, 1, 2)
    mesh, _ = AD.split(mesh, [0])
    at_side = [e for e in range(len(mesh)) if mesh.patch[e] == 0 and mesh.box[e, 2] == mesh.cells and mesh.box[e, 1] == 0]
    mesh, _ = AD.split(mesh, at_side)
    coarse = int(np.flatnonzero(mesh.patch == 1)[0])
    pairs = AD.neighbour_pairs(mesh, sides, 2)
    touching = sorted(int(f if e == coarse else e) for e, f in pairs if coarse in (e, f))
    assert len(touching) == 3                                    # two fine and one medium element along the shared edge
    radiosity = np.zeros((len(mesh), 3))
    radiosity[mesh.patch == 1] = 1.0
    positions, colors, corners = R.call_vertex_colors(REF, mesh.quads, np.zeros(len(mesh), dtype=np.int64), radiosity)
    tv = ADD.t_vertices(mesh, sides, corners, 2)
    z = positions[tv.v][:, 2]
    # on the shared edge x = 1: z = 0.25 and 0.5 inside the coarse element's edge; inside patch 0: the medium element's
    on_edge = np.isclose(positions[tv.v][:, 0], 1.0)
    assert sorted(z[on_edge].round(6).tolist()) == [0.25, 0.5] and (tv.host[on_edge] == coarse).all()
    assert len(tv) == 4
    anchored = ADD.anchor(colors, corners, tv, 3)
    a, b = corners[tv.host, tv.side], corners[tv.host, (tv.side + 1) % 4]
    assert np.allclose(anchored[tv.v], (1 - tv.t)[:, None] * anchored[a] + tv.t[:, None] * anchored[b])
    # the coarse element's edge runs from colour 1/2 to 1/2 (both ends shared with patch 0): the T-vertices too
    assert np.allclose(anchored[tv.v[on_edge]], 0.5)
    assert not np.allclose(colors[tv.v[on_edge]], 0.5)          # R5 alone gave them the fine side's average


def test08_the_drawn_mesh_is_watertight(ctx):
    """A mesh of many levels drawn as fans where T-vertices are shows every polygon pixel; drawn as quads, pinholes."""
    from cs451.stages.radiosity import display as D
    from cs451.stages.radiosity.bench_peer import polygon_ids

    scene = load_scene("cornell-box")
    patches = R.make_patches(scene, REF, 100.0)
    mesh = AD.initial_mesh(patches.quads, 1, 4)
    rng = np.random.default_rng(1)
    for _ in range(4):
        mesh, _ = AD.split(mesh, np.flatnonzero(rng.random(len(mesh)) < 0.3))
    m = len(mesh)
    sol = AD.AdaptiveSolution(mesh, patches.parent[mesh.patch], np.ones((m, 3)), np.zeros((m, 3)),
                              np.zeros((len(patches), 3)), True, 0.0, 0, 0, 0.0, [], AD.shared_sides(patches.quads, patches.parent))
    drawer = D.GouraudDrawer(ctx)
    size = (256, 256)
    shown = polygon_ids(scene, size, drawer=drawer) >= 0
    holes = {}
    for anchored in (False, True):
        image = ADD.draw(scene, REF, sol, len(patches), size, anchored=anchored, drawer=drawer)
        holes[anchored] = int((shown & (image.sum(axis=-1) == 0)).sum())
    assert np.allclose(image[shown], 1 / math.pi, atol=1e-6)     # fans and anchoring keep a constant constant
    assert holes[True] == 0, holes
    assert holes[False] > 0                                      # measured: 2 pinholes, at T-vertices


@pytest.mark.slow
def test09_against_mitsuba_adaptive_has_less_error_where_the_shadows_are():
    pytest.importorskip("mitsuba")
    result = ADR.compare_adaptive(REF, quick=True)
    rows = {row["method"]: row for row in result["rows"]}
    uniform, adaptive = rows["uniform"], rows["adaptive"]
    assert adaptive["elements"] <= uniform["elements"]
    # measured (quick: 128 × 128, 64 spp): floor 15.0% → 10.0%, image 10.6% → 9.7%
    assert adaptive["errors"]["floor"] < 0.8 * uniform["errors"]["floor"]
    assert adaptive["errors"]["image"] < uniform["errors"]["image"]


@pytest.mark.spawns
def test10_the_mesh_figure_and_table_are_the_kits_own(tmp_path):
    """The handout shows the bench's figure in a kit block, the bench writes it there; a student's release has neither."""
    from cs451 import KIT_ROOT
    from cs451.packaging.handout import KIT_BLOCK
    from cs451.packaging.release import build_release

    text = (KIT_ROOT / "assignments" / "04-radiosity" / "README.md").read_text()
    link = f"]({ADR.HANDOUT_FIGURE.parent.name}/{ADR.HANDOUT_FIGURE.name})"
    assert ADR.HANDOUT_FIGURE.is_file() and ADR.HANDOUT_FIGURE.parent.parent == KIT_ROOT / "assignments" / "04-radiosity"
    assert any(link in block for block in KIT_BLOCK.findall(text)), "the figure belongs in a <!-- kit --> block"
    out = build_release("radiosity", tmp_path / "repo")
    shipped = out / "assignments" / "04-radiosity"
    assert not (shipped / ADR.HANDOUT_FIGURE.parent.name).exists()
    assert ADR.HANDOUT_FIGURE.name not in (shipped / "README.md").read_text()
