"""Solves release the GIL: threads solve independent problems at the same time.

    PYTHONPATH=build/python python3 examples/python/parallel_solves.py
"""
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np

import timeopt

rng = np.random.default_rng(1)
problems = []
for _ in range(16):
    waypoints = np.cumsum(rng.uniform(-4, 4, size=(11, 3)) * [1, 1, 0.3], axis=0)
    curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
    problems.append(timeopt.TemporalProblem(curve, timeopt.Limits(max_velocity=3, max_acceleration=2), K=200))

for workers in (1, 2):
    start = time.perf_counter()
    with ThreadPoolExecutor(workers) as pool:
        results = list(pool.map(lambda p: timeopt.Solver("socp").solve(p), problems))
    print(f"{workers} thread(s): {time.perf_counter() - start:.3f} s, T = {sum(r.total_time for r in results):.6f}")
