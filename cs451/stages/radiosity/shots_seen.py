"""What a probe sees of a shooting loop through its ``on_shot`` (R3, R6, R7 promise a call after every shot)."""
from __future__ import annotations

import numpy as np


class ShotsSeen:
    """The ``on_shot`` a probe hands a shooting loop: each call's (shots, i), and the radiosity of the last."""
    def __init__(self, emission: np.ndarray):
        self.calls: list[tuple[int, int]] = []
        self.last = np.full_like(emission, np.nan)

    def __call__(self, shots: int, i: int, radiosity: np.ndarray, unshot: np.ndarray) -> None:
        self.calls.append((int(shots), int(i)))
        self.last = np.array(radiosity, dtype=np.float64)

    def outputs(self) -> dict[str, np.ndarray]:
        """What a probe returns of it: every call's (shots, i) as ``(k, 2) int``, and the radiosity at the last call
        ``(n, 3)`` (NaN where no call came)."""
        return {"on_shot_calls": np.asarray(self.calls, dtype=np.int64).reshape(-1, 2), "on_shot_last": self.last}
