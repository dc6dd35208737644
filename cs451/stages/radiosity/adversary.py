"""The least answer of the right form for each of this stage's tasks, as the body of its function (identity
matrices, empty meshes, misses, unchanged inputs): the attack tests grade a submission made of them, which
must score 0 (a check that passes on nothing would give it points)."""

HEADER = ""

NOTHING = {
    'R1': 'q = np.asarray(quads, float)\n    return q.copy(), np.arange(len(q))',
    'R2': 'return np.array(radiosity, float), np.array(unshot, float)',
    'R3': 'return np.array(emission, float), np.zeros_like(np.array(emission, float)), []',
    'R4': 'return np.zeros(3)',
    'R6': 'return np.array(emission, float), np.zeros_like(np.array(emission, float)), []',
    'R7': 'return np.array(emission, float), np.zeros_like(np.array(emission, float)), []',
    'R5': ('q = np.asarray(quads, float)\n    return q.reshape(-1, 3), '
           'np.repeat(np.asarray(radiosity, float), 4, axis=0),'
           ' np.arange(4 * len(q)).reshape(-1, 4)'),
}
