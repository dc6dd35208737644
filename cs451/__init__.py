"""cs451-kit: the engine every part of the course kit imports.

The engine holds no solution. It reads scenes, opens headless GL contexts,
writes and compares images, declares each stage's interface, and runs the CLI.
"""
import importlib
import sys
from pathlib import Path
from types import ModuleType

__version__ = "0.1.0"

#: The engine's own folder (what the grader copies into a sandbox and a release ships).
ENGINE_DIR = Path(__file__).resolve().parent
#: Engine folders only instructors use (the slides' builder, its vendored reveal.js and KaTeX): never in a student
#: release or a grading sandbox, and not part of the answers' version. Within a stage's package, its deck figures
#: (``stages/<stage>/figures.py``, ``figure_*.py``), its benchmarks (``bench.py``, ``bench_*.py``: their solvers
#: would answer tasks) and its speed layer (``stages/<stage>/accel/``: compiled code that does tasks' work) are
#: instructors' too: see :func:`instructor_only`.
INSTRUCTOR_ONLY = ("slides",)
#: A stage's own folder of compiled speed-ups for its reference (one declared hook: ``Stage.accelerator``).
SPEED_LAYER = "accel"
#: A stage's files only instructors use: its deck figures and its benchmarks (by name, and by prefix for their parts).
INSTRUCTOR_FILES = ("figures.py", "bench.py")
INSTRUCTOR_PREFIXES = ("figure_", "bench_")


def instructor_only(path: Path) -> bool:
    """Whether a file or folder of the engine is only for instructors (the slides and every stage's deck figures,
    which draw from the reference; a stage's benchmarks and speed layer, which would answer its tasks): left out of
    releases, sandboxes and the answers' version."""
    try:
        parts = path.resolve().relative_to(ENGINE_DIR).parts
    except ValueError:
        return False
    if parts and parts[0] in INSTRUCTOR_ONLY:
        return True
    if len(parts) >= 3 and parts[0] == "stages" and parts[2] == SPEED_LAYER:
        return True
    return len(parts) == 3 and parts[0] == "stages" and (parts[2] in INSTRUCTOR_FILES
                                                         or parts[2].startswith(INSTRUCTOR_PREFIXES))


def instructor_paths() -> list[Path]:
    """The instructors-only folders and files this engine holds (:func:`instructor_only`): what a grading sandbox must
    not read wherever the engine lies (a checkout the uid fallback can see, a wheel inside a bound environment)."""
    found = [ENGINE_DIR / name for name in INSTRUCTOR_ONLY if (ENGINE_DIR / name).exists()]
    stages = ENGINE_DIR / "stages"
    for folder in sorted(p for p in stages.iterdir() if p.is_dir()) if stages.is_dir() else []:
        found += [entry for entry in sorted(folder.iterdir()) if instructor_only(entry)]
    return found


def _kit_root() -> Path:
    """Where reference/, starter/, autograder/ and the handouts are.

    In a checkout, an editable install or a student's release, the folder above the engine (it holds
    pyproject.toml). In an installed wheel (``pip install .``), the ``cs451_kit`` folder the wheel puts
    beside the engine (see setup.py).
    """
    beside = ENGINE_DIR.parent
    if (beside / "pyproject.toml").is_file():
        return beside
    installed = beside / "cs451_kit"
    return installed if (installed / "KIT").is_file() else beside


#: The kit this engine serves: a checkout, a student's release, or the kit an installed wheel carries.
KIT_ROOT = _kit_root()


def import_from_kit(module: str) -> ModuleType:
    """Import ``module`` of one of the kit's own top-level packages (``autograder``, ``bench``) from KIT_ROOT.

    Those packages sit beside the engine, not inside it, so they import only with KIT_ROOT on
    ``sys.path``. ``python -m cs451`` run from the kit's folder has it there by chance (the working
    directory comes first); the installed ``cs451`` console script does not, and neither does any
    command run from another folder. Every import of a spec, a check, a truth or a benchmark goes
    through here, so none depends on where the command was typed.
    """
    top = module.split(".")[0]
    root = str(KIT_ROOT)
    if root not in sys.path:
        sys.path.insert(0, root)
    loaded = sys.modules.get(top) or importlib.import_module(top)
    found = [Path(p).resolve() for p in getattr(loaded, "__path__", [])]
    if (KIT_ROOT / top).resolve() not in found:   # another folder's package of that name came first
        from .errors import KitError
        raise KitError(f"{top}: imported from {', '.join(map(str, found)) or '?'}, not from the kit at {KIT_ROOT}; "
                       f"run the command from another folder")
    return importlib.import_module(module)
