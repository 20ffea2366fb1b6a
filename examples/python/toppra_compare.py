"""Side by side with TOPP-RA on the same path and per-axis limits, if toppra is installed.

    PYTHONPATH=build/python python3 examples/python/toppra_compare.py

TOPP-RA (pip install toppra; not a Debian package) parameterizes a path through the same
waypoints; both get per-axis velocity and acceleration limits. Without toppra it says so and
exits 0.
"""
import importlib.util
import sys
import time

import numpy as np

import timeopt

if importlib.util.find_spec("toppra") is None:
    print("toppra is not installed (pip install toppra): skipped")
    sys.exit(0)
import toppra  # noqa: E402
import toppra.algorithm  # noqa: E402
import toppra.constraint  # noqa: E402

waypoints = np.array([[0, 0, 1], [4, 2, 1.5], [8, -1, 1], [12, 0, 2]], dtype=float)
vmax, amax, K = np.array([2.0, 2.0, 1.0]), np.array([1.5, 1.5, 1.0]), 100

curve = timeopt.Curve.from_waypoints(waypoints, kind="cubic")
start = time.perf_counter()
ours = timeopt.solve(timeopt.TemporalProblem(curve, timeopt.Limits(max_velocity=vmax, max_acceleration=amax, max_jerk=None), K=K,
                                             constraint_mode="certified"))
ours_seconds = time.perf_counter() - start

# The same curve for TOPP-RA: its path parameter is our global sigma in [0, pieces].
sigma = np.linspace(0, curve.num_pieces, 20 * K + 1)
path = toppra.SplineInterpolator(sigma, curve.evaluate(sigma))
constraints = [toppra.constraint.JointVelocityConstraint(np.stack([-vmax, vmax], axis=1)),
               toppra.constraint.JointAccelerationConstraint(np.stack([-amax, amax], axis=1))]
start = time.perf_counter()
algorithm = toppra.algorithm.TOPPRA(constraints, path, gridpoints=np.linspace(0, curve.num_pieces, K * curve.num_pieces + 1))
trajectory = algorithm.compute_trajectory(0, 0)
toppra_seconds = time.perf_counter() - start
print(f"timeopt (certified): T = {ours.total_time:.4f} s in {ours_seconds * 1e3:.1f} ms")
print(f"TOPP-RA:             T = {trajectory.duration:.4f} s in {toppra_seconds * 1e3:.1f} ms")
