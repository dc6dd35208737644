"""cs451-kit: the engine every part of the course kit imports.

The engine holds no solution. It reads scenes, opens headless GL contexts,
writes and compares images, declares each stage's interface, and runs the CLI.
"""
from pathlib import Path

__version__ = "0.1.0"

#: The kit checkout this package lives in (reference/, starter/, autograder/ are beside it).
KIT_ROOT = Path(__file__).resolve().parent.parent
