"""A plan across the shipped forest, flown by the simulated quadrotor, plotted with matplotlib.

    PYTHONPATH=build/python python3 examples/python/plan_forest.py [OUTPUT.png]
"""
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402

import timeopt  # noqa: E402

root = os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "..")
forest = timeopt.OccupancyMap.load(os.path.join(root, "maps", "forest_20x20.bt"))
plan = timeopt.plan(forest, [1, 1, 1.5], [19, 19, 1.5], max_velocity=2, max_acceleration=2, max_jerk=10)
if not plan.is_success():
    sys.exit(f"plan failed: {plan.status}: {plan.message}")
trajectory = plan.trajectory()
report = timeopt.simulate(trajectory, timeopt.Limits(max_velocity=2, max_acceleration=2, max_jerk=10))
# The simulated vehicle tracks with a 10 rad/s loop, so it exceeds the limits slightly where the
# reference's jerk changes fast; `timeopt plan` reports the same flight "within 1%".
print(f"T = {plan.total_time:.3f} s, length {plan.path_length:.2f} m; flown: max |v|/vmax "
      f"{report.max_velocity_ratio:.4f}, max |a|/amax {report.max_acceleration_ratio:.4f}")

ts = np.linspace(0, trajectory.duration, 600)
p, v, a, _ = trajectory.sample(ts)
esdf = timeopt.Esdf.from_map(forest)
xs, ys = np.meshgrid(np.linspace(0, 20, 200), np.linspace(0, 20, 200))
slice_points = np.stack([xs.ravel(), ys.ravel(), np.full(xs.size, 1.5)], axis=1)
distance = esdf.distance(slice_points).reshape(xs.shape)

fig, (top, speed) = plt.subplots(1, 2, figsize=(11, 5))
top.contourf(xs, ys, distance, levels=20, cmap="viridis")
top.contour(xs, ys, distance, levels=[0.0], colors="k")
top.plot(p[:, 0], p[:, 1], "r-", label="trajectory")
top.set_aspect("equal")
top.set_title("distance field at z = 1.5 m")
top.legend()
speed.plot(ts, np.linalg.norm(v, axis=1), label="|v| (m/s)")
speed.plot(ts, np.abs(a).max(axis=1), label="max axis |a| (m/s²)")
speed.set_xlabel("t (s)")
speed.legend()
output = sys.argv[1] if len(sys.argv) > 1 else "plan_forest.png"
fig.savefig(output, dpi=100)
print("written:", output)
