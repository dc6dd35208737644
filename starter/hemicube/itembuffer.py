"""H4 and H5: drawing patch ids instead of colours, and summing the delta form factors of what each hemicube saw."""
from __future__ import annotations

import numpy as np


def item_buffer_shaders():
    """GLSL (vertex_source, fragment_source) that draw an item buffer: each pixel holds the id of the patch it sees.

    The kit puts ``#version 330`` and this interface in front of your vertex shader::

        in vec3 in_position;          // a corner of a patch, world coordinates
        in uint in_id;                // the index of its patch, 0 .. n-1
        mat4 hemicube_view();         // this face's view matrix (your H2)
        mat4 hemicube_projection();   // this face's projection (your H3)

    and this in front of your fragment shader::

        out uint item;                // write 0 for "no patch", k + 1 for patch k

    A patch seen from behind (its back face) hides what lies behind it but receives nothing:
    write 0 there. The id goes from one shader to the other in a ``flat`` uint variable, and
    unsigned literals are written 1u, 0u. The kit turns on the z-buffer and decides where each
    face lands (keeping the winding, so ``gl_FrontFacing`` is the patch's front).
    """
    # TODO H4: transform by projection × view, pass the id flat, write id + 1 on front faces (handout §H4)
    raise NotImplementedError("H4: transform by projection × view, pass the id flat, write id + 1 on front faces (handout §H4)")


def form_factor_row(top_items, side_items, top_weights, side_weights, n_patches):
    """The row F_i· of one hemicube: the sum of the delta form factors of the cells that see each patch.

    ``top_items`` (r, r) and ``side_items`` (4, r/2, r) are the item buffers (np.uint32:
    0 = nothing, k + 1 = patch k); ``top_weights`` and ``side_weights`` are the tables of
    H1, shaped like one top face and one side face: the side table serves all four side
    faces. Returns a float array of shape (n_patches,), 0 for a patch no cell sees. No
    Python loop over pixels: a 512-resolution hemicube has 786,432 cells.
    """
    # TODO H5: np.bincount of the ids weighted by the delta form factors, then drop bin 0 (handout §H5)
    raise NotImplementedError("H5: np.bincount of the ids weighted by the delta form factors, then drop bin 0 (handout §H5)")
