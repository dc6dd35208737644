"""The decks' figures: what the kit's reference draws and measures, made through the stage interfaces, cached.

``render_figure(name, cache)`` returns a PNG; :data:`FIGURES` names them (each stage declares its own in
``cs451/stages/<stage>/figures.py``, found through the registry of stages), each with one line that says what
it shows. Every figure is drawn by the reference through its stage's interface (``get_stage(...)``: the
stage's ``render``, its probes, ``Stage.call`` and ``functions_replaced``, its diagrams), the hemicube
engine's pictures (:mod:`cs451.formfactors.pictures`) and the engine's drawing (:mod:`cs451.stages.radiosity.display`), so a change
to the reference changes the slides. Timings are never measured while a deck is built: the benchmark figures draw
only from records (``slides/records/<name>.json``, :mod:`cs451.slides.records`) that ``cs451 slides record`` made,
each naming its machine, date and command.

The cache key of a figure is a hash of what made it: its name and parameters, the bundled scene files and
records it reads, and the source text of the reference packages and kit modules that draw it (this module included).
Change one function of ``reference/hemicube`` and every figure drawn with it is made again; change a
handout and none is. The PNG carries its key and the numbers it shows (a row sum, counters, timings) as
text chunks: :func:`figure_facts` reads them back.

Ray tracing figures run the reference's plain numpy path (its speed layer held off: ``accel.forced``): it gives
the same colours as the compiled kernels (tests/whitted/test_whitted_frame.py), takes a few seconds at slide sizes (renders
are made at twice their shown size), and never waits for numba's first compile (~2 minutes on two cores); the path
tracer's figure (128 passes of 208 × 208) takes about a minute. Not thread-safe: build figures in one thread, or in
processes.
"""
from __future__ import annotations

import hashlib
import importlib.util
import json
import os
import re
import tempfile
from pathlib import Path
from typing import Any

import numpy as np

from .. import KIT_ROOT
from ..errors import KitError
from ..impl import earlier_stage_impl
from ..progress import Progress
from ..scene import BUNDLED_DIR
from . import canvas, registry
from .registry import SPECS, Drawn, Spec, spec_of
FORMAT = 3                  # 2: figures at twice their shown size, with their smallest text noted; 3: measured
                            # figures drawn from records (slides/records), text never under canvas.MIN_FONT_PT

# --- the cache ------------------------------------------------------------------------------------------

def _module_file(name: str) -> Path:
    spec = importlib.util.find_spec(name)
    if spec is None or spec.origin is None:
        raise KitError(f"figure sources: no module {name!r}")
    return Path(spec.origin)


def _package_files(folder: Path, label: str) -> list[tuple[str, Path]]:
    if not (folder / "__init__.py").is_file():
        raise KitError(f"{folder}: no reference package here (the figures draw with the kit's reference)")
    return [(f"{label}/{p.relative_to(folder).as_posix()}", p) for p in sorted(folder.rglob("*.py"))
            if "__pycache__" not in p.parts]


def figure_sources(name: str) -> list[tuple[str, Path]]:
    """Every file whose text enters figure ``name``'s cache key, labelled: reference packages, kit and bench
    modules, scene files, recorded measurements, the module that draws it, and the figures' shared modules (this
    one included)."""
    spec = spec_of(name)
    files = [item for stage in spec.stages for item in _package_files(registry.REFERENCE / stage, f"reference/{stage}")]
    files += [item for stage in spec.engine
              for item in _package_files(earlier_stage_impl(stage), f"kit reference/{stage}")]
    modules = dict.fromkeys((*spec.kit, spec.draw.__module__, "cs451.slides.canvas", "cs451.slides.registry", __name__))
    files += [(module, _module_file(module)) for module in modules]
    files += [(f"bench/{module}.py", KIT_ROOT / "bench" / f"{module}.py") for module in spec.bench]
    files += [(f"scenes/{scene}", BUNDLED_DIR / scene) for scene in spec.scenes]
    if spec.records:
        from . import records
        files += [(f"slides/records/{name}.json", records.record_path(name, must_exist=True)) for name in spec.records]
    return files


def figure_key(name: str, quick: bool = False) -> str:
    """The hash of what makes figure ``name``: its parameters and the text of :func:`figure_sources`."""
    spec = spec_of(name)
    digest = hashlib.sha256()
    head = {"format": FORMAT, "figure": name, "quick": bool(quick), "params": spec.quick if quick else spec.full}
    digest.update(json.dumps(head, sort_keys=True, default=str).encode())
    for label, path in figure_sources(name):
        try:
            data = path.read_bytes()
        except OSError as err:
            raise KitError(f"figure {name!r}: cannot read {path} ({err.strerror or err})") from None
        digest.update(f"\n{label}\n{len(data)}\n".encode())
        digest.update(data)
    return digest.hexdigest()


def render_figure(name: str, cache: Path, quick: bool = False) -> Path:
    """The PNG of figure ``name`` in ``cache``: drawn when no PNG there has the key of what makes it now.

    ``quick``: the tests' small version (its own file). A figure drawn again replaces its older PNGs.
    """
    spec = spec_of(name)
    key = figure_key(name, quick)
    stem = f"{name}-quick" if quick else name
    cache = Path(cache)
    path = cache / f"{stem}-{key[:16]}.png"
    if path.is_file():
        return path
    bar = Progress(f"figure {name}", spec.steps)
    canvas.TEXT_PX.clear()
    try:
        with canvas.readable():
            drawn = spec.draw(bar, **(spec.quick if quick else spec.full))
    finally:
        bar.close()
    _write_png(path, drawn, spec, key, min(canvas.TEXT_PX, default=None))
    for old in cache.glob(f"{stem}-*.png"):
        if old != path and re.fullmatch(rf"{re.escape(stem)}-[0-9a-f]{{16}}", old.stem):
            old.unlink(missing_ok=True)
    return path


def _write_png(path: Path, drawn: Drawn, spec: Spec, key: str, text_px: float | None) -> None:
    """Write through a temporary file of our own, so that a reader never sees half a PNG."""
    from PIL import Image, PngImagePlugin

    info = PngImagePlugin.PngInfo()
    info.add_text("Title", spec.name)
    info.add_text("Description", spec.description)
    info.add_text("cs451:key", key)
    info.add_text("cs451:facts", json.dumps(drawn.facts, sort_keys=True, default=float))
    # the smallest text drawn on a canvas, in the PNG's pixels, 0 for none (the readability check)
    info.add_text("cs451:text_px", f"{text_px or 0:.2f}")
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(prefix=f".{path.stem}-", suffix=".png", dir=path.parent)
    try:
        with os.fdopen(fd, "wb") as out:
            Image.fromarray(np.ascontiguousarray(drawn.image[..., :3], dtype=np.uint8)).save(out, "PNG", pnginfo=info)
        os.replace(tmp, path)
    except BaseException:
        Path(tmp).unlink(missing_ok=True)
        raise


def figure_facts(path: Path) -> dict[str, Any]:
    """The numbers a figure's PNG shows (row sums, counters, timings), and its key, as written with it."""
    from PIL import Image

    with Image.open(path) as image:
        text = dict(getattr(image, "text", {}))
    return {**json.loads(text.get("cs451:facts", "{}")), "key": text.get("cs451:key")}




def _declared() -> dict[str, Any]:
    """Every stage's figures, loaded from the stage's own package (``figures.py`` beside its interface)."""
    from ..stages import stage_names
    from ..stages.base import part
    for name in stage_names():
        if importlib.util.find_spec(f"cs451.stages.{name}.figures") is not None:
            part(f"cs451.stages.{name}", "figures")
    return SPECS


FIGURES: dict[str, str] = {name: spec.description for name, spec in _declared().items()}
