"""The least answer of the right form for each of this stage's tasks, as the body of its function (identity
matrices, empty meshes, misses, unchanged inputs): the attack tests grade a submission made of them, which
must score 0 (a check that passes on nothing would give it points)."""

HEADER = ""

NOTHING = {
    'W1': ('n = width * height\n    return np.tile(np.asarray(camera.eye, float), (n, 1)),'
           ' np.tile([0.0, 0.0, -1.0], (n, 1))'),
    'W2': 'n = len(origins)\n    return np.full(n, np.inf), np.full(n, np.inf)',
    'W3': 'return np.full(len(origins), np.inf)',
    'W4': ("n = len(lo)\n    return {'lo': lo.min(axis=0)[None], 'hi': hi.max(axis=0)[None], 'child': np.array([-1]),"
           " 'start': np.array([0]), 'count': np.array([n]), 'order': np.arange(n)}"),
    'W5': 'n = len(origins)\n    return np.full(n, np.inf), np.full(n, -1), np.zeros((n, 3))',
    'W6': 'return np.zeros((len(normals), 3))',
    'W7': "scene.counters['shadow'] += len(origins)\n    return np.ones((len(origins), 3))",
    'W8': 'return np.asarray(directions, float)',
    'W9': 'd = np.asarray(directions, float)\n    return d, np.zeros(len(d), bool)',
    'W10': 'return np.zeros(np.shape(cos_i))',
    'W11': "scene.counters['camera'] += len(origins)\n    return np.zeros((len(origins), 3))",
    'W12': 'return np.zeros((len(directions), 3)), np.asarray(directions, float)',
}
