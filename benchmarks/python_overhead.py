"""The Python module's overhead on a temporal solve, in one run: the same problem (m = 10 pieces,
K = 50, paper rows, a minimum-jerk curve through a random walk) solved by a reusable Solver from a
Python loop, and by the same kind of solver in a C++ loop (timeopt.time_solves). Prints medians.

    PYTHONPATH=build/python python3 benchmarks/python_overhead.py [--repeats N] [--mode paper|certified]
"""
import argparse
import statistics
import time

import numpy as np

import timeopt

parser = argparse.ArgumentParser()
parser.add_argument("--repeats", type=int, default=200)
parser.add_argument("--mode", default="paper", choices=["paper", "certified"])
args = parser.parse_args()

rng = np.random.default_rng(5)
waypoints = np.cumsum(rng.uniform(-4, 4, size=(11, 3)) * [1, 1, 0.3], axis=0)
curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
problem = timeopt.TemporalProblem(curve, timeopt.Limits(max_velocity=[3, 3, 2], max_acceleration=[2, 2, 1.5]), K=50,
                                  constraint_mode=args.mode)
solver = timeopt.Solver("socp")
for _ in range(20):  # warm up both
    solver.solve(problem)
timeopt.time_solves(problem, "socp", 20)

rounds = []
for _ in range(5):  # interleaved rounds: both see the same machine state
    python = []
    for _ in range(args.repeats):
        start = time.perf_counter()
        result = solver.solve(problem)
        _ = result.total_time, result.piece_durations
        python.append(time.perf_counter() - start)
    cpp = timeopt.time_solves(problem, "socp", args.repeats)
    rounds.append((statistics.median(python), statistics.median(cpp)))
py_median = statistics.median(r[0] for r in rounds)
cpp_median = statistics.median(r[1] for r in rounds)
print(f"m = 10, K = 50, {args.mode} rows, T = {result.total_time:.6f} s, {args.repeats} solves x 5 rounds")
print(f"python loop: {py_median * 1e3:.4f} ms median; C++ loop: {cpp_median * 1e3:.4f} ms median; "
      f"overhead {100 * (py_median / cpp_median - 1):+.2f}%")
