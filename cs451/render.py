"""``cs451 render``: render a scene with an implementation of a stage and write a PNG."""
from __future__ import annotations

import time
from pathlib import Path

from .errors import KitError
from .imageio import save_png
from .limits import check_image_size
from .impl import load_impl, resolve_impl
from .scene import load_scene
from .stages import check_options, get_stage, stage_names
from .stages.base import check_not_empty


def parse_size(text: str | None) -> tuple[int, int] | None:
    """'640x480' to (640, 480)."""
    if text is None:
        return None
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise KitError(f"--size: expected WIDTHxHEIGHT such as 640x480, got {text!r}") from None
    if w <= 0 or h <= 0:
        raise KitError(f"--size: {w}x{h} is not a usable image size")
    problem = check_image_size(w, h, "--size")
    if problem:
        raise KitError(problem)
    return w, h


def infer_stage(scene) -> str:
    """The stage to draw a scene with when ``--stage`` is not given, asked of the stages: the one its ``options``
    name among those that draw it; none named, the first that draws it; several named, the user chooses."""
    check_not_empty(scene)
    drawing = [name for name in stage_names() if get_stage(name).draws_scene(scene)]
    named = [name for name in drawing if name in scene.options]
    if len(named) > 1:
        raise KitError(f"{scene.label}: its options name stages {', '.join(named)}; choose one with --stage")
    if named or drawing:
        return (named or drawing)[0]
    raise KitError(f"{scene.label}: no stage draws every object and light in it (stages: {', '.join(stage_names())})")


def render_scene(*, scene: str, output: str | Path, impl: str = "reference", size: str | None = None,
                 stage: str | None = None, shading: str | None = None) -> tuple[Path, float]:
    """Render ``scene`` (a bundled name or a JSON path) and write ``output``; returns the path and seconds."""
    from .copy import student_stage
    from .imageio import check_output
    check_output(output)
    sc = load_scene(scene)
    check_options(sc)
    st = get_stage(stage or student_stage() or infer_stage(sc))
    st.check_scene(sc)
    st.check_cost(sc, parse_size(size))
    module = load_impl(resolve_impl(impl, st.name), st.name)
    start = time.perf_counter()
    if shading and "shading" not in getattr(st.options_type, "__dataclass_fields__", {}):
        raise KitError(f"--shading: stage {st.number} ({st.name}) has no shading option (stage 1 has)")
    kwargs = {"shading": shading} if shading else {}
    image = st.render(sc, module, parse_size(size), **kwargs)
    seconds = time.perf_counter() - start
    return save_png(output, image, sc.image.exposure, sc.image.srgb), seconds


def figure_stage(figure: str) -> str:
    """The stage whose task a figure's number names (``S5.3``: stage 1's S5)."""
    from .copy import student_stage
    mine = student_stage()
    if mine:
        return mine
    task = figure.split(".")[0]
    for name in stage_names():
        if any(t.id == task for t in get_stage(name).tasks):
            return name
    raise KitError(f"--figure {figure}: no stage has a task {task!r}; a figure is named by its test, e.g. S5.1")


def render_figure(*, figure: str, output: str | Path, impl: str = "reference") -> tuple[Path, float]:
    """Draw a handout figure with an implementation, exactly as its image test draws it; returns the path and seconds.

    A figure (``assignments/<handout>/figures/<test>.png``) is the reference's answer to a public image test:
    that test's scene, size and settings (``patch_size``, ``resolution``, shading…), and the parts of earlier
    tasks the test gives (the reference's own, so that a figure judges its task alone). They are in the
    public tests (``autograder/<stage>/public.json`` in a student's copy), and this draws the same with
    ``impl``, written as the figure is: ``cs451 compare`` then judges the two as the test does.
    """
    from .grading.checks import target_images
    from .grading.expected import ReferenceAnswers
    from .grading.loader import load_tests
    from .imageio import check_output
    from .packaging.figures import is_image_test
    check_output(output)
    st = get_stage(figure_stage(figure))
    figures = [t for t in load_tests(st.name, include_hidden=False) if is_image_test(t)]
    test = next((t for t in figures if t.number == figure), None)
    if test is None:
        raise KitError(f"--figure {figure}: not a figure of stage {st.name} (its figures: "
                       f"{', '.join(t.number for t in figures) or 'none'})")
    module = load_impl(resolve_impl(impl, st.name), st.name)
    given = ReferenceAnswers(st.name).get(test.given, test.params) if test.given else {}
    start = time.perf_counter()
    outputs = st.probes[test.probe](module, **test.params, **given)
    seconds = time.perf_counter() - start
    image = target_images(outputs, test.params).get("reference")
    if image is None:
        raise KitError(f"--figure {figure}: {st.name}'s {test.task} drew no image (as the test would report)")
    return save_png(output, image), seconds
