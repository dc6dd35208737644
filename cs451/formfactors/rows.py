"""Rows of the form-factor matrix by hemicubes: lazily, cached, many hemicubes per read-back, with checks.

Rows are computed only when asked and cached; only geometry enters, so changing
colours, albedos or emission reuses every row. Each row is the student's H5 summed
over a hemicube the atlas renders. Proximity: the hemicube treats the shooter as a
point at its centre, an error no resolution fixes when another patch is close to it;
``proximity="contour"`` replaces the form factor to every close patch by the area
average over the shooter (Gauss points) of the exact point-to-polygon form factor
(H6) times the fraction of it visible from each point (:mod:`.proximity`); ``shooter_split=k``
averages k × k hemicubes spread over the shooter instead.
"""
from __future__ import annotations

import time
from typing import Any, Iterable

import numpy as np

from ..errors import KitError
from ..patches import as_quads, patch_areas, patch_centers, patch_normals
from .atlas import ItemBufferRenderer, one_thread_product
from .device_reduction import DeviceReduction, supports_device_reduction
from .reduction import AtlasReduction
from .calls import StageCalls
from .grids import patch_grids
from .geometry import _sub_quads, default_near_far, hemicube_up
from .proximity import fix_row

REDUCTIONS = ("stage", "atlas", "device")
BATCHES_AT_ONCE = 8      # batches whose rows are summed in one go (pipelined): their dense rows are in memory together
BLIND_ROW_SUM = 0.05  # a row summing to less sees (almost) nothing: with resample_blind, look again from over the patch


class HemicubeFormFactors:
    """Rows of the form-factor matrix of ``quads`` by hemicubes, lazily, cached, many hemicubes per read-back.

    Parameters: ``calls`` the stage-3 implementation's answers (:class:`~.calls.StageCalls`); ``resolution`` cells across the
    top face (even); ``near`` the near plane (default 1e-3 of the scene's diagonal);
    ``rotate`` a seeded random rotation of each hemicube about its normal (breaks
    aliasing between the cells and regular geometry); ``proximity`` "contour" (exact
    point-to-polygon form factors averaged over the shooter for close pairs, H6) or
    "none"; ``proximity_distance`` how close is close, in shooter radii (centre to
    farthest corner) between the shooter's centre and the receiver's bounding sphere;
    ``batch`` hemicubes per read-back (capped by the atlas size); ``shooter_split`` k renders
    k × k hemicubes per row, at the centres of the shooter's k × k sub-quads, and averages
    their rows by area (the other answer to the proximity error, and to occluders close to
    the shooter, at k² the cost). ``resample_blind`` k (0: off): a row that sees almost
    nothing from the patch centre (sum under ``BLIND_ROW_SUM``) is looked at again from the
    centres of k × k sub-quads, and the rows of those that see are averaged by area. A patch
    whose centre lies under a box resting on it (a floor patch straddling a block's footprint)
    is lit on its exposed part, and that part must shoot its light; from the centre alone the
    light would vanish. ``cull`` draws each hemicube face with only the patches that can land in it
    (:class:`~.atlas.ItemBufferRenderer`): the same rows, for trusted shaders only. ``reduction`` "stage"
    sums each hemicube with the stage's H5 (``calls.row``: a submission's rows are its own); "atlas" sums a
    whole batch where it was read back (:class:`~.reduction.AtlasReduction`), "device" on the GPU with a compute
    shader (:class:`~.device_reduction.DeviceReduction`): H5's rows to float64 rounding, without a copy or a call
    per hemicube. ``grids`` draws each polygon's grid of patches as one quad whose fragments find their patch
    (:mod:`.grids`): the rows of the same hemicubes but for pixels on patch edges, at a fraction of the triangles.
    All three need ``trusted`` (the kit's own stage-3 code); left as None they are chosen with the GL context: on
    a CPU rasteriser culled, grids and "atlas"; on a GPU unculled, patch by patch and "device" (4.3 and up).

    ``counters``: hemicubes_rendered (k² per row with a split shooter), rows_computed,
    rows_cached_hits (rows asked for again), patches_culled (summed over rows: patches wholly
    in or behind the shooter's plane, which the base-plane clip discards), patches_backfacing
    (in front of the plane but facing away: drawn, they hide what is behind them, receive 0),
    proximity_pairs (close pairs the contour fix replaced), blind_rows_resampled, readbacks (one per batch).
    ``seconds``: render (draw and read back; the renderer's own ``seconds`` split them), sum (H5 or the atlas
    reduction), proximity (the fix).
    """

    def __init__(self, quads: Any, calls: StageCalls, resolution: int = 128, near: float | None = None, rotate: bool = True,
                 seed: int = 0, proximity: str = "contour", batch: int = 256, proximity_distance: float = 2.0,
                 shooter_split: int = 1, resample_blind: int = 0, ctx: Any = None, cull: bool | None = None,
                 reduction: str | None = None, trusted: bool = False, grids: bool | None = None):
        self.quads = as_quads(quads)
        if len(self.quads) == 0:
            raise KitError("no patches")
        if int(resolution) != resolution or resolution < 2 or resolution % 2:
            raise KitError(f"hemicube resolution must be an even integer >= 2, got {resolution}")
        if reduction not in (None, *REDUCTIONS):
            raise KitError(f"reduction must be one of {', '.join(REDUCTIONS)}, got {reduction!r}")
        if (cull or grids or reduction not in (None, "stage")) and not trusted:
            raise KitError("culling, grids and the engine's own reductions are for trusted stage-3 code only (trusted=True)")
        self.trusted = bool(trusted)
        self._cull_request, self._reduction_request, self._grids_request = cull, reduction, grids
        #: decided with the GL context (:attr:`renderer`): whether faces are culled, and how rows are summed
        self.cull: bool | None = None
        self.grids: bool | None = None
        self.reduction: str | None = None
        self._reducer: Any = None                       # the engine's reduction, made at first use
        if proximity not in ("contour", "none"):
            raise KitError(f"proximity must be 'contour' or 'none', got {proximity!r}")
        self.calls = calls
        self.n = len(self.quads)
        self.resolution = int(resolution)
        self.rotate, self.seed, self.proximity = bool(rotate), int(seed), proximity
        self.proximity_distance = float(proximity_distance)
        if int(shooter_split) != shooter_split or shooter_split < 1:
            raise KitError(f"shooter_split must be a positive integer, got {shooter_split}")
        self.shooter_split = int(shooter_split)
        if int(resample_blind) != resample_blind or resample_blind < 0:
            raise KitError(f"resample_blind must be a non-negative integer, got {resample_blind}")
        self.resample_blind = int(resample_blind)
        self.normals = patch_normals(self.quads)
        self.areas = patch_areas(self.quads)
        self.centers = patch_centers(self.quads)
        self.radii = np.linalg.norm(self.quads - self.centers[:, None, :], axis=2).max(axis=1)
        d_near, self.far = default_near_far(self.quads)
        self.near = d_near if near is None else float(near)
        if not 0 < self.near < self.far:
            raise KitError(f"near plane must lie in (0, {self.far:g}), got {self.near}")
        self._batch_request = max(1, min(int(batch), self.n))   # no bigger an atlas than the scene needs
        self._ctx = ctx
        self._renderer: ItemBufferRenderer | None = None
        self._tables: tuple[np.ndarray, np.ndarray] | None = None
        self._rows: dict[int, np.ndarray] = {}
        self.counters = {"hemicubes_rendered": 0, "rows_computed": 0, "rows_cached_hits": 0, "patches_culled": 0,
                         "patches_backfacing": 0, "proximity_pairs": 0, "proximity_kernel_pairs": 0, "proximity_evaluations": 0,
                         "blind_rows_resampled": 0, "readbacks": 0}
        self.seconds = {"render": 0.0, "sum": 0.0, "proximity": 0.0}

    # -- lazily built GPU state ------------------------------------------------
    @property
    def tables(self) -> tuple[np.ndarray, np.ndarray]:
        if self._tables is None:
            self._tables = self.calls.tables(self.resolution)
        return self._tables

    @property
    def renderer(self) -> ItemBufferRenderer:
        if self._renderer is None:
            from ..gl import create_context, is_software
            ctx = self._ctx or create_context()
            software = is_software(ctx)
            # trusted code, by default: on a CPU rasteriser, cull (each face draws only what can land in it) and
            # sum on the CPU; on a GPU, one instanced draw of everything and the sums on the device
            cull = self._cull_request if self._cull_request is not None else self.trusted and software
            reduction = self._reduction_request or ("stage" if not self.trusted else "atlas" if software
                                                    or not supports_device_reduction(ctx) else "device")
            if reduction == "device" and not supports_device_reduction(ctx):
                raise KitError(f"the device reduction needs OpenGL 4.3; this context is {ctx.version_code}")
            grids = self._grids_request if self._grids_request is not None else self.trusted and software
            self.cull, self.reduction, self.grids = bool(cull), reduction, bool(grids)
            projections = self.calls.projections(self.near, self.far)
            self._renderer = ItemBufferRenderer(self.quads, self.calls.shaders(), self.resolution, projections,
                                                self._batch_request, ctx, cull=self.cull,
                                                grids=patch_grids(self.quads) if self.grids else None)
        return self._renderer

    # -- rows --------------------------------------------------------------------
    def row(self, i: int) -> np.ndarray:
        """Row F_i· (n,): computed on first request, then cached; a read-only view of the cache (a shooting loop
        asks for rows thousands of times: no copy each time)."""
        cached = self._rows.get(int(i)) if isinstance(i, (int, np.integer)) else None
        if cached is None:
            return self.rows([i])[0]
        self.counters["rows_cached_hits"] += 1
        view = cached.view()
        view.flags.writeable = False
        return view

    def has_row(self, i: int) -> bool:
        """Whether row i is rendered already (asking for it costs nothing)."""
        return int(i) in self._rows

    def rows(self, indices: Iterable[int]) -> np.ndarray:
        """Rows (k, n) for ``indices``; the missing ones are rendered in batches (many hemicubes per read-back)."""
        idx = [int(i) for i in indices]
        for i in idx:
            if not 0 <= i < self.n:
                raise KitError(f"patch index {i} out of range 0 .. {self.n - 1}")
        missing = list(dict.fromkeys(i for i in idx if i not in self._rows))
        self.counters["rows_cached_hits"] += len(idx) - len(missing)
        if missing:
            group = BATCHES_AT_ONCE * self.renderer.batch     # drawn while the last batch is summed; bounded memory
            for start in range(0, len(missing), group):
                self._compute(missing[start:start + group])
        out = np.zeros((len(idx), self.n))
        for k, i in enumerate(idx):
            out[k] = self._rows[i]
        return out

    def matrix(self) -> np.ndarray:
        """The full matrix F (n, n); F[i, j] is the fraction of the energy leaving i that reaches j."""
        return self.rows(range(self.n))

    def cached(self) -> list[int]:
        """Indices of the rows computed so far."""
        return sorted(self._rows)

    def matches(self, quads: Any) -> bool:
        """Whether ``quads`` is this object's geometry: then every cached row still holds, whatever the
        colours, albedos or emission (form factors depend on geometry only), and the object can be reused."""
        q = np.asarray(quads, dtype=np.float64)
        return q.shape == self.quads.shape and bool(np.array_equal(q, self.quads))

    def views_for(self, i: int, point: np.ndarray | None = None) -> np.ndarray:
        """The five views (H2) of patch i's hemicube, at its centre or at ``point`` on it."""
        return self._views(self.centers[i] if point is None else point, self.normals[i], i)

    def _views(self, eye: np.ndarray, normal: np.ndarray, index: int) -> np.ndarray:
        """The five views (H2) of a hemicube at ``eye`` facing ``normal``, turned by hemicube ``index``'s seeded rotation."""
        return self.calls.views(eye, normal, hemicube_up(normal, index, self.rotate, self.seed))

    def shooter_points(self, i: int, split: int | None = None) -> tuple[np.ndarray, np.ndarray]:
        """Where patch i's hemicubes stand: its centre, or with ``shooter_split`` k (or ``split``) the centres of
        its k × k bilinear sub-quads, with their area weights (summing to 1)."""
        split = self.shooter_split if split is None else split
        if split == 1:
            return self.centers[i][None], np.ones(1)
        sub = _sub_quads(self.quads[i], split)
        areas = patch_areas(sub)
        return patch_centers(sub), areas / areas.sum()

    def item_buffers(self, indices: Iterable[int]) -> tuple[np.ndarray, np.ndarray]:
        """The item buffers of the hemicubes at the centres of patches ``indices``, as rows are computed from them:
        tops (k, r, r) and sides (k, 4, r/2, r), uint32 (0: nothing, j + 1: patch j). For the grader's trusted inputs."""
        idx = [int(i) for i in indices]
        r, tops, sides = self.resolution, [], []
        for start in range(0, len(idx), self.renderer.batch):
            chunk = idx[start:start + self.renderer.batch]
            views = np.stack([self.views_for(i) for i in chunk])
            planes = np.array([[*self.normals[i], float(self.normals[i] @ self.centers[i])] for i in chunk])
            for top, side in self.renderer.render(views, planes):
                tops.append(top)
                sides.append(side)
        return (np.asarray(tops, dtype=np.uint32).reshape(-1, r, r),
                np.asarray(sides, dtype=np.uint32).reshape(-1, 4, r // 2, r))

    def proximity_fixed(self, i: int, row: np.ndarray) -> np.ndarray:
        """Row ``row`` of patch i (from its hemicube) with the proximity fix applied to its close patches (H6)."""
        return self._proximity_fix(int(i), np.asarray(row, dtype=np.float64))

    def rows_at(self, points: Any, normals: Any, lift: Any = 0.0, ids: Any = None) -> np.ndarray:
        """Rows (k, n) for shooters that are not among the receivers: one hemicube at each point.

        For substructuring, where a patch shoots to the finer elements it is made of: the
        hemicube stands at the patch's centre, facing its normal, and sees the receivers
        (``quads``). ``lift`` (k,) raises each base plane, so that the shooter's own elements,
        which lie in (or, on a slightly warped quad, a hair above) that plane, are not drawn.
        ``ids`` (k,) pick each hemicube's seeded rotation (default 0 .. k-1): give every shooter
        its own, or their aliasing lines up. Not cached, and not counted as rows of this matrix.
        """
        points = np.asarray(points, dtype=np.float64).reshape(-1, 3)
        normals = np.asarray(normals, dtype=np.float64).reshape(-1, 3)
        lift = np.broadcast_to(np.asarray(lift, dtype=np.float64), (len(points),))
        normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
        ids = range(len(points)) if ids is None else [int(i) for i in np.ravel(ids)]
        jobs = [(k, points[k], normals[k], float(normals[k] @ points[k] + lift[k]), i, 1.0) for k, i in enumerate(ids)]
        return self._render_rows(jobs, len(points))

    def _render_rows(self, jobs: list, count: int) -> np.ndarray:
        """Sum hemicube rows: jobs are (row, eye, normal, plane offset, rotation index, weight)."""
        rows = np.zeros((count, self.n))
        top_w, side_w = self.tables
        step = self.renderer.batch
        chunks = [jobs[start:start + step] for start in range(0, len(jobs), step)]
        if self.reduction != "stage":
            self._sum_atlases(chunks, rows)
            return rows
        for chunk in chunks:
            t0 = time.perf_counter()
            buffers = self.renderer.render(*self._batch_views(chunk))
            t1 = time.perf_counter()
            for (k, _, _, _, _, w), (top, sides) in zip(chunk, buffers):
                rows[k] += w * self.calls.row(top, sides, top_w, side_w, self.n)
            self._count_batch(chunk, t1 - t0, time.perf_counter() - t1)
        return rows

    def _batch_views(self, chunk: list) -> tuple[np.ndarray, np.ndarray]:
        """The views (B, 5, 4, 4) and base planes (B, 4) of a batch of jobs."""
        views = np.stack([self._views(eye, n, index) for _, eye, n, _, index, _ in chunk])
        return views, np.array([[*n, d] for _, _, n, d, _, _ in chunk])  # the base plane from the geometry, not H2

    def _count_batch(self, chunk: list, render: float, total: float) -> None:
        """Count a batch's hemicubes and read-back, and its seconds drawing and reading back, and summing."""
        self.counters["readbacks"] += 1
        self.counters["hemicubes_rendered"] += len(chunk)
        self.seconds["render"] += render
        self.seconds["sum"] += total

    def _sum_atlases(self, chunks: list, rows: np.ndarray) -> None:
        """The engine's own reduction (``atlas`` or ``device``), pipelined: batch k + 1 is drawn while batch k is summed."""
        renderer = self.renderer
        if self._reducer is None and self.reduction == "device":
            try:
                self._reducer = DeviceReduction(renderer.ctx, *self.tables, renderer.cols, self.n, renderer.batch)
            except Exception as err:       # noqa: BLE001 - a driver that will not build it: the same rows on the CPU
                from ..progress import warn
                warn(f"form factors: the GPU's compute shader failed ({str(err).strip().splitlines()[0]}); "
                     f"summing rows on the CPU instead")
                self.reduction = "atlas"
        if self._reducer is None:
            self._reducer = AtlasReduction(*self.tables, renderer.cols, self.n)
        pending = None
        for chunk in [*chunks, None]:
            t0 = time.perf_counter()
            ticket = renderer.submit(*self._batch_views(chunk)) if chunk is not None else None
            self.seconds["render"] += time.perf_counter() - t0
            if pending is not None:
                done, (slot, height) = pending
                t1 = time.perf_counter()
                if self.reduction == "device":                 # the wait for the draw counts as summing here
                    t2 = t1
                    found = self._reducer.rows(renderer.texture((slot, height)), len(done), height)
                else:
                    atlas = renderer.collect((slot, height))
                    t2 = time.perf_counter()
                    found = self._reducer.rows(atlas, len(done))
                for (k, _, _, _, _, w), row in zip(done, found):
                    rows[k] += w * row
                self._count_batch(done, t2 - t1, time.perf_counter() - t2)
            pending = (chunk, ticket) if chunk is not None else None

    def _compute(self, batch: list[int]) -> None:
        jobs = [(k, p, self.normals[i], float(self.normals[i] @ self.centers[i]), i, w)
                for k, i in enumerate(batch) for p, w in zip(*self.shooter_points(i))]
        rows = self._render_rows(jobs, len(batch))
        stands: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        if self.resample_blind:
            blind = [k for k, i in enumerate(batch) if rows[k].sum() < BLIND_ROW_SUM]
            if blind:
                for k, found in zip(blind, self._resampled_rows([batch[k] for k in blind])):
                    if found is not None:
                        rows[k], stands[k] = found
        t2 = time.perf_counter()
        self._count_culled(batch)
        for k, i in enumerate(batch):
            self._rows[i] = self._proximity_fix(i, rows[k], stands.get(k)) if self.proximity == "contour" else rows[k]
            self.counters["rows_computed"] += 1
        self.seconds["proximity"] += time.perf_counter() - t2

    def _resampled_rows(self, patches: list[int]) -> list[tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None]:
        """Rows of patches blind from their centres: the area-weighted mean over the sub-quad centres that see, with
        those centres and their weights (None where none sees: the patch faces an opening, and its centre's row stands)."""
        points = [self.shooter_points(i, self.resample_blind) for i in patches]
        stands = [(i, p) for i, (ps, _) in zip(patches, points) for p in ps]
        jobs = [(k, p, self.normals[i], float(self.normals[i] @ self.centers[i]), i, 1.0) for k, (i, p) in enumerate(stands)]
        sub = self._render_rows(jobs, len(jobs))
        out: list[tuple[np.ndarray, tuple[np.ndarray, np.ndarray]] | None] = []
        start = 0
        for ps, weights in points:
            rows = sub[start:start + len(ps)]
            start += len(ps)
            sums = rows.sum(axis=1)
            seeing = sums >= max(0.5 * sums.max(), BLIND_ROW_SUM)
            w = weights[seeing] / weights[seeing].sum() if seeing.any() else weights
            out.append((w @ rows[seeing], (ps[seeing], w)) if seeing.any() else None)
        self.counters["blind_rows_resampled"] += len(patches)
        return out

    def _count_culled(self, batch: list[int]) -> None:
        """Count, for the shooters ``batch``, the patches wholly behind their planes and those facing away."""
        corners = self.quads.reshape(-1, 3)
        own = np.einsum("jd,jd->j", self.centers, self.normals)                              # n_j · c_j
        for start in range(0, len(batch), 256):                                             # (256, n) at a time
            b = np.asarray(batch[start:start + 256])
            n_c = np.einsum("bd,bd->b", self.normals[b], self.centers[b])                  # (B,)
            top = one_thread_product(corners, self.normals[b].T).reshape(self.n, 4, -1).max(axis=1).T - n_c[:, None]
            behind = top <= 1e-9 * np.maximum(self.radii[b], 1e-300)[:, None]            # (B, n): highest corner
            behind[np.arange(len(b)), b] = False                                         # not the shooter itself
            self.counters["patches_culled"] += int(behind.sum())
            facing_away = own - one_thread_product(self.centers[b], self.normals.T) >= 0    # (c_j - c_b) · n_j >= 0
            self.counters["patches_backfacing"] += int((facing_away & ~behind).sum())

    def _proximity_fix(self, i: int, row: np.ndarray, stands: tuple[np.ndarray, np.ndarray] | None = None) -> np.ndarray:
        """Row i corrected for the shooter's extent (:mod:`.proximity`), measured from ``stands`` (points, weights):
        by default where its hemicubes stand (:meth:`shooter_points`)."""
        return fix_row(self.calls, self.quads, self.normals, self.centers, self.radii, i, row,
                       self.shooter_points(i) if stands is None else stands, self.proximity_distance, self.counters,
                       float(self.tables[0].max()))

    # -- checks reported for every run ----------------------------------------------
    def report(self) -> dict[str, Any]:
        """Row sums, reciprocity (A_i F_ij against A_j F_ji over pairs whose rows are both computed), closure."""
        done = self.cached()
        if not done:
            return {"rows": 0, **self.counters}
        F = np.stack([self._rows[i] for i in done])
        sums = F.sum(axis=1)
        idx = np.array(done)
        sub = F[:, idx] * self.areas[idx, None]              # A_i F_ij for i, j both computed
        diff = np.abs(sub - sub.T)
        scale = np.maximum(sub, sub.T)
        # the max is over pairs that both see each other clearly; the total weighs every pair
        significant = np.minimum(sub, sub.T) > 1e-3 * max(scale.max(), 1e-300)
        recip_rel = float((diff[significant] / scale[significant]).max()) if significant.any() else 0.0
        recip_total = float(diff.sum() / max(2 * sub.sum(), 1e-300))
        return {"rows": len(done), "row_sum_min": float(sums.min()), "row_sum_max": float(sums.max()),
                "row_sum_mean": float(sums.mean()), "closure_error_max": float(np.abs(1 - sums).max()),
                "reciprocity_error_max": recip_rel, "reciprocity_error_total": recip_total,
                "resolution": self.resolution, **self.counters}

    def summary(self) -> str:
        r = self.report()
        if not r["rows"]:
            return "no rows computed yet"
        return (f"{r['rows']} rows at resolution {self.resolution}: row sums {r['row_sum_min']:.4f} .. {r['row_sum_max']:.4f}, "
                f"reciprocity error max {r['reciprocity_error_max']:.2%} (total {r['reciprocity_error_total']:.2%}); "
                f"{r['hemicubes_rendered']} hemicubes in {r['readbacks']} read-backs, {r['rows_cached_hits']} cache hits, "
                f"{r['patches_culled']} patches culled, {r['proximity_pairs']} close pairs fixed")
