"""Writes a CBF whose KKT factor fills in: N variables, N three-dimensional second-order cones each
over a random triple of them, a random objective (the problem is unbounded; it is for the factor's
size, not its answer). With N = 10,000 (a 746 KB file) the sparse factor has 4.02 million
non-zeros after fill-in (about 107 MiB): `timeopt conic FILE --max-memory 150` refuses it before
allocating it (docs/sizes-and-errors.md).

    PYTHONPATH=build/python python3 benchmarks/conic_fill_in_cbf.py 10000 fill.cbf
"""
import sys

import numpy as np
import scipy.sparse as sp

import timeopt

n, path = int(sys.argv[1]), sys.argv[2]
rng = np.random.default_rng(0)
rows, cols = [], []
for k in range(n):
    for r, v in enumerate(rng.choice(n, 3, replace=False)):  # s = h - G x in the cone: x_t, x_a, x_b
        rows.append(3 * k + r)
        cols.append(v)
G = sp.csc_matrix((-np.ones(len(rows)), (rows, cols)), shape=(3 * n, n))
h = np.tile([1.0, 0.0, 0.0], n)
timeopt.conic.write_cbf(path, rng.uniform(-1, 1, n), G, h, cones={"q": [3] * n})
