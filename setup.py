"""Builds the instructor's wheel: the engine (``cs451``) and, beside it, the kit it runs (``cs451_kit``).

Metadata is in pyproject.toml. What is here is what a declarative file cannot say: a wheel must carry the
kit's folders (reference/, starter/, autograder/, assignments/, bench/, setup.sh), which are not Python
packages of the engine, so that ``pip install .`` gives a ``cs451`` that can render and grade away from the
checkout. They go to a folder ``cs451_kit`` beside ``cs451`` in site-packages (never inside the engine,
which the grader copies into every sandbox). Such a wheel holds the reference solutions and the hidden
tests: it is the instructor's and is never published (README, "Installing").

The build runs in a private temporary folder (``tempfile.mkdtemp``: mode 0700, a fresh name), removed when
``setup()`` returns, so ``pip install .`` leaves no ``build/`` in the checkout and no readable copy of the kit
in ``/tmp`` (the uid-only sandbox cannot hide one, and its canary refuses to grade where it finds one).
"""
from __future__ import annotations

import shutil
import tempfile
from pathlib import Path

from setuptools import setup
from setuptools.command.build_py import build_py

HERE = Path(__file__).resolve().parent
#: the kit's folders and files a working install needs (slides/: the decks), copied as they are (no caches)
KIT_PARTS = ("reference", "starter", "autograder", "assignments", "bench", "docs", "slides", "setup.sh",
             "pyproject.toml", "README.md")
LITTER = shutil.ignore_patterns("__pycache__", "*.pyc", ".cs451-cache", "*.egg-info")


class build_py_with_kit(build_py):
    """build_py, plus the kit's folders copied to ``cs451_kit/`` in the wheel."""

    def run(self) -> None:
        super().run()
        target = Path(self.build_lib) / "cs451_kit"
        shutil.rmtree(target, ignore_errors=True)
        target.mkdir(parents=True)
        for part in KIT_PARTS:
            source = HERE / part
            if source.is_dir():
                shutil.copytree(source, target / part, ignore=LITTER)
            elif source.is_file():
                shutil.copy2(source, target / part)
        (target / "KIT").write_text("the cs451 kit installed beside its engine; see cs451/__init__.py\n")


BUILD = Path(tempfile.mkdtemp(prefix="cs451-kit-build-"))
try:
    setup(cmdclass={"build_py": build_py_with_kit},
          options={"build": {"build_base": str(BUILD)}, "bdist_wheel": {"bdist_dir": str(BUILD / "wheel")}})
finally:
    shutil.rmtree(BUILD, ignore_errors=True)
