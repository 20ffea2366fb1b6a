"""The smallest use: a curve through waypoints, limits, the time-optimal profile, samples.

    PYTHONPATH=build/python python3 examples/python/minimal_solve.py
"""
import numpy as np

import timeopt

waypoints = np.array([[0, 0, 1], [4, 2, 1.5], [8, -1, 1], [12, 0, 2]], dtype=float)
curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
limits = timeopt.Limits(max_velocity=2.0, max_acceleration=1.5, max_jerk=8.0)
problem = timeopt.TemporalProblem(curve, limits, K=50, constraint_mode="certified")
result = timeopt.solve(problem)  # or solver="ipopt"
print(result, "pieces:", np.round(result.piece_durations, 3))
if result.status == timeopt.TemporalStatus.optimal:
    trajectory = timeopt.Trajectory(curve, result)
    p, v, a, j = trajectory.sample(np.linspace(0, trajectory.duration, 200))
    print("max |v| per axis:", np.abs(v).max(axis=0), "max |a| per axis:", np.abs(a).max(axis=0))
