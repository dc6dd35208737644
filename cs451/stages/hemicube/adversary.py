"""The least answer of the right form for each of this stage's tasks, as the body of its function (identity
matrices, empty meshes, misses, unchanged inputs): the attack tests grade a submission made of them, which
must score 0 (a check that passes on nothing would give it points)."""

#: what the bodies below name (the submission's module defines them)
HEADER = '''ITEM_VS = "void main() { gl_Position = vec4(0.0, 0.0, 0.0, 1.0); }"
ITEM_FS = "void main() { item = 0u; }"
'''

NOTHING = {
    'H1': 'r = int(resolution)\n    return np.zeros((r, r)), np.zeros((r // 2, r))',
    'H2': 'return np.stack([np.eye(4)] * 5)',
    'H3': 'return np.stack([np.eye(4)] * 2)',
    'H4': 'return ITEM_VS, ITEM_FS',
    'H5': 'return np.zeros(n_patches)',
    'H6': 'return 0.0',
    'H7': 'return np.zeros((resolution, resolution))',
}
