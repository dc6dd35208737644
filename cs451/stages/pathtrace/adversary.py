"""The least answer of the right form for each of this stage's tasks, as the body of its function (straight up, no
light, every path ended, black): the attack tests grade a submission made of them, which must score 0."""

HEADER = ""

NOTHING = {
    'P1': 'n = np.asarray(normals, float)\n    return n.copy()',
    'P2': 'return np.zeros((len(points), 3))',
    'P3': 'w = np.asarray(weights, float)\n    return np.zeros(len(w), bool), np.zeros_like(w)',
    'P4': 'return np.zeros((len(origins), 3))',
    'P5': 'return np.zeros((len(points), 3))',
}
