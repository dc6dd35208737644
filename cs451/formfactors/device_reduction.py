"""Rows summed on the device: a compute shader adds each atlas pixel's delta form factor to its row.

Only the rows come back (count · n · 8 bytes), not the pixels (count · 3r² · 4 bytes): at resolution 128 and
2,408 patches a batch of 256 reads back 4.9 MB instead of 50 MB. Each invocation walks a run of pixels along a
tile row, adds up the weights of each stretch of one item in double precision, and adds the stretch to the row
as a 64-bit fixed-point number (2^-62 units) made of two 32-bit atomic adds with the carry passed on. Integer
additions commute, so the rows are the same bits whatever order the GPU runs the invocations in; they agree
with H5's float64 sums to about 1e-16 (``tests/hemicube/test_formfactors.py``). Needs OpenGL 4.3 (compute shaders);
macOS stops at 4.1, and there the engine sums on the CPU (:mod:`.reduction`).
"""
from __future__ import annotations

from typing import Any

import numpy as np

FIXED = float(2 ** 62)     # fixed-point units per form factor: rows sum to about 1, so 2 bits of headroom
RUN = 16                   # pixels per invocation (divides any even resolution's tile width at 16 and up)

_SHADER = """#version 430
layout(local_size_x = 8, local_size_y = 8) in;
layout(r32ui, binding = 0) readonly uniform uimage2D u_atlas;
layout(std430, binding = 1) buffer Rows { uint rows[]; };             // (count, n, 2): low, high words
layout(std430, binding = 2) readonly buffer Weights { double weights[]; };   // (3r, r): one tile
uniform int u_r;
uniform int u_cols;
uniform int u_count;
uniform int u_n;
uniform int u_run;
uniform int u_height;

void add(uint b, uint item, double s) {
    double units = s * 4611686018427387904.0lf;                        // 2^62
    double high = floor(units / 4294967296.0lf);
    uint low = uint(units - high * 4294967296.0lf);
    uint at = 2u * (b * uint(u_n) + item - 1u);
    uint before = atomicAdd(rows[at], low);
    atomicAdd(rows[at + 1u], uint(high) + (before + low < before ? 1u : 0u));   // the carry out of the low word
}

void main() {
    int y = int(gl_GlobalInvocationID.y);
    int x0 = int(gl_GlobalInvocationID.x) * u_run;
    if (y >= u_height || x0 >= u_cols * u_r) return;
    int tx = x0 / u_r, ty = y / (3 * u_r);
    int b = ty * u_cols + tx;
    if (b >= u_count) return;
    int w0 = (y - ty * 3 * u_r) * u_r + (x0 - tx * u_r);
    uint current = 0u;
    double s = 0.0;
    for (int k = 0; k < u_run; k++) {
        uint item = imageLoad(u_atlas, ivec2(x0 + k, y)).x;
        if (item != current) {
            if (current != 0u && current <= uint(u_n)) add(uint(b), current, s);
            current = item;
            s = 0.0;
        }
        s += weights[w0 + k];
    }
    if (current != 0u && current <= uint(u_n)) add(uint(b), current, s);
}
"""


def supports_device_reduction(ctx: Any) -> bool:
    """Whether ``ctx`` runs compute shaders (OpenGL 4.3) with double precision, as this reduction needs."""
    return int(getattr(ctx, "version_code", 0)) >= 430


class DeviceReduction:
    """Rows (count, n) of a batch, summed on the device from an atlas texture laid out as
    :class:`~.reduction.AtlasReduction` describes; ``batch`` tiles at most."""

    def __init__(self, ctx: Any, top: np.ndarray, side: np.ndarray, cols: int, n: int, batch: int):
        top, side = np.asarray(top, dtype=np.float64), np.asarray(side, dtype=np.float64)
        self.ctx, self.r, self.cols, self.n = ctx, top.shape[1], int(cols), int(n)
        self.run = RUN if self.r % RUN == 0 else self.r
        self.program = ctx.compute_shader(_SHADER)
        weights = np.ascontiguousarray(np.concatenate([top, side, side, side, side]))     # (3r, r)
        self.weights = ctx.buffer(weights.tobytes())
        self.rows_buffer = ctx.buffer(reserve=int(batch) * self.n * 8)
        for name, value in (("u_r", self.r), ("u_cols", self.cols), ("u_n", self.n), ("u_run", self.run)):
            self.program[name].value = value

    def rows(self, texture: Any, count: int, height: int) -> np.ndarray:
        """Rows (count, n), float64, of the first ``count`` tiles of ``texture`` (R32UI), ``height`` rows of it used."""
        from ..gl import make_current
        make_current(self.ctx)
        size = count * self.n * 8
        self.rows_buffer.clear(size=size)
        texture.bind_to_image(0, read=True, write=False)
        self.rows_buffer.bind_to_storage_buffer(1)
        self.weights.bind_to_storage_buffer(2)
        self.program["u_count"].value = int(count)
        self.program["u_height"].value = int(height)
        runs = -(-self.cols * self.r // self.run)
        self.program.run(-(-runs // 8), -(-height // 8))
        self.ctx.memory_barrier()
        words = np.frombuffer(self.rows_buffer.read(size=size), dtype=np.uint32).reshape(count, self.n, 2)
        return (words[..., 1].astype(np.float64) * 2.0 ** 32 + words[..., 0]) / FIXED
