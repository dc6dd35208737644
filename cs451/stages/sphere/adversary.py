"""The least answer of the right form for each of this stage's tasks, as the body of its function (identity
matrices, empty meshes, misses, unchanged inputs): the attack tests grade a submission made of them, which
must score 0 (a check that passes on nothing would give it points)."""

#: what the bodies below name (the submission's module defines them)
HEADER = '''VS = "void main() { gl_Position = u_projection * u_model_view * vec4(in_position, 1.0); }"
FS = "void main() { frag_color = vec4(0.0, 0.0, 0.0, 1.0); }"
'''

NOTHING = {
    'S1': 'return np.eye(4)',
    'S2': 'return np.eye(4)',
    'S3': "return np.zeros((sum(1 for c in calls if c[0] == 'draw'), 4, 4))",
    'S4': 'return np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3), dtype=int)',
    'S5': 'return VS, FS',
    'S6': 'return VS, FS',
    'S7': 'return (0, 0, 0, 0), np.eye(4)',
    'S8': 'return state',
    'S9': 'return np.eye(4)',
}
