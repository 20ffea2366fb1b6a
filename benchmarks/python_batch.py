"""timeopt.solve_many on a Dask LocalCluster of 1 and of 2 worker processes (one thread each), and
on 1 and 2 threads in this process: 200 jerk-limited problems (minimum-jerk curves through 11
random waypoints, m = 10 pieces, K = 50, certified rows), wall time of the whole batch, medians of
`--rounds` rounds taken in turn. Checks that every run gives the loop's T, to the bit.

    PYTHONPATH=build/python python3 benchmarks/python_batch.py [--problems 200] [--rounds 5]

Needs Debian's python3-distributed. A benchmark, not a test: ctest does not run it.
"""
import argparse
import statistics
import time

import numpy as np
from distributed import Client, LocalCluster

import timeopt


def problems(count):
    rng = np.random.default_rng(7)
    out = []
    for _ in range(count):
        waypoints = np.cumsum(rng.uniform(-4, 4, size=(11, 3)) * [1, 1, 0.3], axis=0)
        curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
        limits = timeopt.Limits(max_velocity=3, max_acceleration=2, max_jerk=10)
        out.append(timeopt.TemporalProblem(curve, limits, K=50, constraint_mode="certified"))
    return out


def main():
    parser = argparse.ArgumentParser()
    parser.add_argument("--problems", type=int, default=200)
    parser.add_argument("--rounds", type=int, default=5)
    args = parser.parse_args()
    batch = problems(args.problems)
    truth = [r.total_time for r in timeopt.solve_many(batch, threads=1)]

    # One cluster alive at a time (the idle one's processes would share the two cores), each
    # round taking the four runs in turn.
    def on_cluster(workers):
        with LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None) as cluster:
            with Client(cluster) as client:
                timeopt.solve_many(batch, client=client)  # warm up: the workers import timeopt
                start = time.perf_counter()
                results = timeopt.solve_many(batch, client=client)
                return time.perf_counter() - start, results

    def on_threads(threads):
        start = time.perf_counter()
        results = timeopt.solve_many(batch, threads=threads)
        return time.perf_counter() - start, results

    runs = {"1 process": lambda: on_cluster(1), "2 processes": lambda: on_cluster(2),
            "1 thread": lambda: on_threads(1), "2 threads": lambda: on_threads(2)}
    seconds = {name: [] for name in runs}
    for _ in range(args.rounds):
        for name, run in runs.items():
            elapsed, results = run()
            seconds[name].append(elapsed)
            assert [r.total_time for r in results] == truth, name

    median = {name: statistics.median(s) for name, s in seconds.items()}
    print(f"{args.problems} jerk-limited problems (m = 10, K = 50), medians of {args.rounds} rounds:")
    for name, value in median.items():
        print(f"  {name:12s} {value:7.3f} s  ({1e3 * value / args.problems:.2f} ms per problem)")
    print(f"  2 processes / 1 process: {median['1 process'] / median['2 processes']:.2f} x faster")
    print(f"  2 threads / 1 thread:    {median['1 thread'] / median['2 threads']:.2f} x faster")


if __name__ == "__main__":
    main()
