"""cs451-kit: the engine every part of the course kit imports.

The engine holds no solution. It reads scenes, opens headless GL contexts,
writes and compares images, declares each stage's interface, and runs the CLI.
"""
from pathlib import Path

__version__ = "0.1.0"

#: The engine's own folder (what the grader copies into a sandbox and a release ships).
ENGINE_DIR = Path(__file__).resolve().parent
#: Engine folders only lecturers use (the slides' builder, its vendored reveal.js and KaTeX, the figures it draws
#: from the reference): never in a student release or a grading sandbox, and not part of the answers' version.
LECTURER_ONLY = ("slides",)


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
