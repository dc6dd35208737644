"""The recipe of docs/adding-a-stage.md as data: every file a toy sixth stage writes, and the lines it adds to the
lists of stages a person keeps (the README's table and the like), for ``tests/test_architecture.py`` to apply to a
copy of the kit. The toy is a whole stage, not the least one: a deck with its figure, a demo and a benchmark too.
"""

TOY_STAGE = '''\
"""Stage 6 (a toy, for the architecture test): scale a colour; the image is the scaled colour."""
from __future__ import annotations

from dataclasses import dataclass
from typing import Any

import numpy as np

from ... import schema
from ...errors import KitError
from ...scene import AreaLight, Polygon, Scene
from ...schema import field
from ..base import Out, Probes, Stage, Task, part

TASKS = (Task("T1", "scale", "Scaling a colour", ("values", "factor"), (Out("scaled", ("len(values)",)),)),)


@dataclass(frozen=True)
class ToyOptions:
    factor: float = field("What the colour is scaled by.", 0.5, schema.positive)


def render(scene: Scene, impl: Any, size: tuple[int, int] | None = None, **_: Any) -> np.ndarray:
    """The polygons' mean diffuse colour, scaled by T1; any other kind is refused (a consumer never skips)."""
    for group in ("objects", "lights"):
        for k, item in enumerate(getattr(scene, group)):
            if not isinstance(item, (Polygon, AreaLight)):
                raise KitError(f"{scene.label}: {group}[{k}]: the toy stage has no {type(item).__name__}")
    diffuse = [scene.material(o.material).diffuse for o in scene.objects] or [(0.0, 0.0, 0.0)]
    colour = STAGE.call(impl, "T1", np.mean(diffuse, axis=0), STAGE.options(scene).factor)
    w, h = size or (scene.image.width, scene.image.height)
    return np.broadcast_to(colour, (h, w, 3)).copy()


PROBES = Probes()


@PROBES.register
def probe_scale(impl: Any, values: list, factor: float) -> dict[str, np.ndarray]:
    return {"scaled": STAGE.call(impl, "T1", np.asarray(values, dtype=np.float64), float(factor))}


def run_demo(module: Any, output: Any, window: bool, frames: int | None, scene: str = "cornell-box",
             size: tuple[int, int] | None = None, screenshot: Any = None) -> list:
    """The colour scaled a step at a time (:mod:`.demo`)."""
    return part(__name__, "demo").demo(module, output, window, frames, scene=scene, size=size, screenshot=screenshot)


DEMO_KEYS = (("+ -", "the factor"), ("q", "quits"))

STAGE = Stage(name="toy", number=6, title="A toy stage", handout="06-toy", tasks=TASKS, render=render,
              probes=PROBES, options_type=ToyOptions, draws=(Polygon, AreaLight), demo=run_demo, demo_keys=DEMO_KEYS)
'''

TOY_REFERENCE = '''\
"""The toy stage's solution."""
import numpy as np


def scale(values, factor):
    """``values`` times ``factor`` (handout §T1)."""
    # BEGIN SOLUTION T1: multiply every value by the factor (handout §T1)
    return np.asarray(values, dtype=np.float64) * factor
    # END SOLUTION
'''

TOY_TESTS = '''\
"""Toy {kind} tests."""
from cs451.grading.checks import array_close
from cs451.grading.spec import Test

SCALED = array_close("scaled", truth_key="scaled", what="the scaled values")
TESTS = [Test("T1 scale: {name}", "T1", {points}, "scale", {{"values": {values}, "factor": {factor}}}, SCALED,
              "entries within 1e-6 relative"),
         Test("T1 scale: {name}, negated", "T1", {points}, "scale", {{"values": {values}, "factor": -{factor}}}, SCALED,
              "entries within 1e-6 relative")]
'''

TOY_HANDOUT = '''\
# Stage 6: a toy stage

Scale a colour. Render it with `cs451 render cornell-box --stage toy -o toy.png` and check it with
`cs451 grade toy --public-only`.

| Task | Function | Points |
|---|---|---|
| T1 | `scale` | 100 |
| Total | | 100 |

### T1 Scaling a colour

```python
def scale(values, factor):
```

Return `values` times `factor`.
'''

#: every file the recipe names for a stage called "toy" (the starter is derived by `cs451 starter`)
TOY_DEMO = '''\
"""The toy stage's demo: the colour scaled by the submission's T1, the factor a quarter higher each step."""
from __future__ import annotations

from pathlib import Path
from types import ModuleType

import numpy as np

from ...demos.player import Event, Prepared, play
from ...imageio import to_uint8
from ...scene import load_scene
from .. import toy as T


class ToyDemo(Prepared):
    name = title = "toy"
    caption_lines = 1
    smooth = False

    def __init__(self, module: ModuleType, scene: str | Path = "cornell-box", size: tuple[int, int] | None = None):
        self.scene = load_scene(scene)
        T.STAGE.check_scene(self.scene)
        self.module, self.size, self.factor, self.steps = module, size or (64, 48), 0.0, 0

    def frame_size(self) -> tuple[int, int]:
        return self.size

    def handle(self, event: Event) -> None:
        if event[0] == "key" and event[1] in ("+", "-"):
            self.factor = max(0.0, self.factor + (0.25 if event[1] == "+" else -0.25))

    def busy(self) -> bool:
        return self.steps < 4

    def step(self, seconds: float) -> bool:
        self.steps += 1
        self.factor += 0.25
        return True

    def frame(self) -> np.ndarray:
        colour = np.clip(T.STAGE.call(self.module, "T1", np.full(3, 0.8), self.factor), 0.0, 1.0)
        return to_uint8(np.broadcast_to(colour, (self.size[1], self.size[0], 3)).copy())

    def caption(self) -> str:
        return f"toy · {self.scene.name}: factor {self.factor:g}"

    def script(self) -> list[list[Event]]:
        return [[], [("key", "-")]]


def demo(module: ModuleType, output: Path, window: bool, frames: int | None, scene: str | Path = "cornell-box",
         size: tuple[int, int] | None = None, screenshot: Path | None = None, fullscreen: bool = False) -> list[Path]:
    """In a window until q; headless, a frame a step and one after ``-``, as PNGs and ``toy.gif``."""
    return play(ToyDemo(module, scene, size), window=window, frames=frames, output=output, screenshot=screenshot,
                fullscreen=fullscreen)
'''

TOY_FIGURES = '''\
"""The toy deck's figure: a colour scaled by the reference's T1 at four factors."""
from __future__ import annotations

import numpy as np

from ...progress import Progress
from ...slides.canvas import Panel, panel_grid, reference_impl
from ...slides.registry import Drawn, slide_figure
from .. import get_stage


@slide_figure("toy-scaled", "A grey scaled by the reference's T1 at four factors",
              full={"factors": [0.25, 0.5, 0.75, 1.0], "size": [96, 96]}, quick={"size": [32, 32]},
              stages=("toy",), kit=("cs451.stages.toy",))
def _scaled(bar: Progress, factors: list[float], size: list[int]) -> Drawn:
    stage, impl = get_stage("toy"), reference_impl("toy")
    panels = [Panel((np.clip(stage.call(impl, "T1", np.full(3, 0.8), f), 0, 1) * 255).astype(np.uint8)
                    * np.ones((size[1], size[0], 1), np.uint8), f"x {f:g}") for f in factors]
    bar.advance(note="panels")
    return Drawn(np.asarray(panel_grid([panels], pad=8, min_width=0)), {"factors": factors})
'''

TOY_BENCH = '''\
"""``cs451 bench toy``: T1's time against the length of what it scales."""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from cs451.impl import load_impl, resolve_impl
from cs451.stages.toy import STAGE

#: the top-level keys of toy.json (what a figure or a doc may read)
KEYS = ("rows",)


def main(output: Path, quick: bool = False) -> dict:
    ref = load_impl(resolve_impl("reference", "toy"), "toy")
    rows = []
    for n in ([10, 1000] if quick else [10, 1000, 100000]):
        values = np.linspace(0.0, 1.0, n)
        start = time.perf_counter()
        STAGE.call(ref, "T1", values, 0.5)
        rows.append({"n": n, "seconds": time.perf_counter() - start})
        print(f"{n:>8} values: {rows[-1]['seconds']:.2e} s")
    output.mkdir(parents=True, exist_ok=True)
    (output / "toy.json").write_text(json.dumps({"rows": rows}, indent=1))
    return {"rows": rows}
'''

TOY_DECK = """# Stage 6: a toy stage

---

## Scaling a colour

Task T1 scales a colour by a factor.

![A grey scaled at four factors](figure:toy-scaled){height=300}

Note: The toy stage exists to prove the recipe of adding a stage: its deck shows a figure its own package draws.
"""

RECIPE = {
    "cs451/stages/toy/__init__.py": TOY_STAGE,
    "cs451/stages/toy/adversary.py": 'HEADER = ""\nNOTHING = {"T1": "return np.zeros(3)"}\n',
    "cs451/stages/toy/tolerances.py": ('from ..base import Tolerance\n\nSCALED = Tolerance(1e-12, "a product of two '
                                       'float64 numbers against the same product: rounding only")\n'),
    "reference/toy/__init__.py": "from .scale import scale\n",
    "reference/toy/scale.py": TOY_REFERENCE,
    "autograder/toy/__init__.py": "",
    "autograder/toy/public.py": TOY_TESTS.format(kind="public", name="doubles", points=30, values=[0.1, 0.2, 0.3],
                                                 factor=2.0),
    "autograder/toy/hidden.py": TOY_TESTS.format(kind="hidden", name="halves", points=20, values=[1.0, 3.0],
                                                 factor=0.5),
    "assignments/06-toy/README.md": TOY_HANDOUT,
    "cs451/stages/toy/demo.py": TOY_DEMO,
    "cs451/stages/toy/figures.py": TOY_FIGURES,
    "cs451/stages/toy/bench.py": TOY_BENCH,
    "slides/06-toy.md": TOY_DECK,
}
#: What ``cs451 starter`` derives from the toy's reference.
DERIVED = {"starter/toy/__init__.py", "starter/toy/scale.py"}
#: The lists of stages a person keeps, each checked against the registry (tests/test_stage_lists.py, or the test that
#: reads it): (file, a line already there, the line the recipe adds after it; no line: appended at the end).
EDITS = (
    ("README.md", "| 5 `pathtrace` |", "| 6 `toy` | a toy: a colour scaled | [assignments/06-toy](assignments/06-toy/README.md) |"),
    ("slides/00-overview.md", "| 5 `pathtrace` |", "| 6 `toy` | a toy: a colour scaled | none |"),
    ("docs/lecturers.md", "| `pathtrace` |", "| `toy` | a colour scaled, a step a frame | `+` `-` the factor | `toy.gif` |"),
    ("docs/lecturers.md", "| pathtrace |", "| toy | 2 | 20 |"),
    ("docs/stages.md", None, "## Stage 6: a toy stage (`toy`)\n\nA colour scaled (T1), for the architecture test."),
    ("docs/testing.md", "| `tests/pathtrace/` |", "| `tests/toy/` | stage 6: none of its own |"),
    ("tests/test_demo_screen.py", '"pathtrace": (', '    "toy": ("furnace", "400x300", 400),'),
)


def apply_edit(text: str, anchor: str | None, line: str) -> str:
    """``text`` with ``line`` added after the first line holding ``anchor`` (at the end, without one)."""
    if anchor is None:
        return text.rstrip("\n") + "\n\n" + line + "\n"
    lines = text.split("\n")
    at = next(k for k, old in enumerate(lines) if anchor in old)
    return "\n".join(lines[:at + 1] + [line] + lines[at + 1:])
