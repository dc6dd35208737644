"""``python -m cs451``: the same as the ``cs451`` command (used where the console script is not on PATH)."""
from .cli import main

raise SystemExit(main())
