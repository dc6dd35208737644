"""Wavefront OBJ meshes, read through trimesh, with a bad file's problem named by its line.

trimesh reads the file; where it fails, or reads numbers no renderer can use (NaN, 1e300), the kit finds the
line itself, so the one-line message says where to look: ``torus.obj, line 3: vertex 3 is [nan, 1.0, 0.0]``.
"""
from __future__ import annotations

from pathlib import Path

import numpy as np

from .errors import KitError
from .schema import MAX_MAGNITUDE


#: the largest OBJ file read: about 4 million triangles
MAX_OBJ_BYTES = 256 * 2**20

#: Meshes already read, by (path, modification time, size): a scene rendered again (a demo's frames, the
#: bench's sweeps) does not parse its OBJ again. Callers get copies.
_MESHES: dict[tuple, tuple[np.ndarray, np.ndarray]] = {}


def load_mesh(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    """Vertices and triangles of an OBJ file, through trimesh; a KitError naming the scene field on failure."""
    from .scene import file_kind
    kind = file_kind(path)
    if kind != "file":
        raise KitError(f"{where}: mesh file {path} " + ("not found" if kind == "missing" else f"is {kind}, not a file"))
    stat = path.stat()
    if stat.st_size > MAX_OBJ_BYTES:
        raise KitError(f"{where}: mesh file {path} is {stat.st_size / 2**20:.0f} MB, over the "
                       f"{MAX_OBJ_BYTES // 2**20} MB the kit reads (trimesh holds several times a file's size)")
    key = (str(path.resolve()), stat.st_mtime_ns, stat.st_size)
    if key not in _MESHES:
        if len(_MESHES) >= 8:
            _MESHES.clear()
        _MESHES[key] = _read_mesh(path, where)
    v, f = _MESHES[key]
    return v.copy(), f.copy()


def _read_mesh(path: Path, where: str) -> tuple[np.ndarray, np.ndarray]:
    import trimesh
    try:
        mesh = trimesh.load(path, force="mesh", process=False)
    except Exception as err:  # trimesh raises many kinds on a malformed file: find the line ourselves
        found = _obj_problem(path)
        why = f"{path.name}, line {found[0]}: {found[1]}" if found else f"cannot read {path.name}: {err}"
        raise KitError(f"{where}: {why}") from None
    v, f = np.asarray(mesh.vertices, np.float64), np.asarray(mesh.faces, np.int64)
    if len(f) == 0:
        raise KitError(f"{where}: {path.name} has no triangles")
    bad = np.flatnonzero(~(np.abs(v) <= MAX_MAGNITUDE).all(axis=1))   # NaN fails the comparison too
    if len(bad):
        k = int(bad[0])
        raise KitError(f"{where}: {path.name}, line {_vertex_line(path, k)}: vertex {k + 1} is {v[k].tolist()} "
                       f"(coordinates must be finite numbers within ±{MAX_MAGNITUDE:g})")
    if f.min(initial=0) < 0 or f.max(initial=0) >= len(v):
        found = _obj_problem(path) or (0, f"a face names a vertex it does not have ({len(v)} vertices)")
        raise KitError(f"{where}: {path.name}, line {found[0]}: {found[1]}")
    return v, f


def _obj_problem(path: Path) -> tuple[int, str] | None:
    """The first line of an OBJ file that trimesh could not make sense of, and why: a vertex that is not three
    numbers, a face with fewer than three corners or naming a vertex not yet defined."""
    count = 0
    with path.open(errors="replace") as lines:
        for number, line in enumerate(lines, 1):
            words = line.split()
            if not words or words[0] not in ("v", "f"):
                continue
            if words[0] == "v":
                try:
                    [float(w) for w in words[1:4]]
                except ValueError:
                    return number, f"a vertex must be three numbers, got {line.strip()[:80]!r}"
                if len(words) < 4:
                    return number, f"a vertex must be three numbers, got {line.strip()[:80]!r}"
                count += 1
                continue
            if len(words) < 4:
                return number, f"a face needs at least three corners, got {line.strip()[:80]!r}"
            for word in words[1:]:
                try:
                    index = int(word.split("/")[0])
                except ValueError:
                    return number, f"a face's corners are vertex numbers, got {word[:40]!r}"
                if index == 0 or abs(index) > count:
                    return number, f"vertex {index} does not exist here ({count} vertices defined so far)"
    return None


def _vertex_line(path: Path, k: int) -> int:
    """The line of an OBJ file that defines its vertex number ``k`` (from 0), for a message."""
    with path.open(errors="replace") as lines:
        seen = -1
        for number, line in enumerate(lines, 1):
            if line.startswith("v ") or line.startswith("v\t"):
                seen += 1
                if seen == k:
                    return number
    return 0
