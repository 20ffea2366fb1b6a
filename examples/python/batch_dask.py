"""A parameter study on a Dask cluster: the minimum time of random minimum-jerk paths over a grid of
jerk limits and cells per piece, solved by timeopt.solve_many, written as a CSV.

    PYTHONPATH=build/python python3 examples/python/batch_dask.py                  # a LocalCluster here
    PYTHONPATH=build/python python3 examples/python/batch_dask.py tcp://host:8786  # a running scheduler
    ... [--paths 20] [--workers 2] [-o study.csv]

With no address it starts a LocalCluster of --workers processes on this machine. With an address
the workers must import timeopt themselves (docs/python.md, "Many problems"). Needs Debian's
python3-distributed.
"""
import argparse
import csv
import itertools
import time

import numpy as np
from distributed import Client, LocalCluster

import timeopt


def study(paths):
    """(parameters, problem) for every path x jerk limit x K: a path is a minimum-jerk curve
    through 8 random waypoints (a random walk, flatter in z)."""
    rng = np.random.default_rng(3)
    curves = [timeopt.Curve.from_waypoints(np.cumsum(rng.uniform(-4, 4, size=(8, 3)) * [1, 1, 0.3], axis=0))
              for _ in range(paths)]
    out = []
    for (index, curve), jerk, K in itertools.product(enumerate(curves), (5.0, 10.0, 20.0), (20, 50)):
        limits = timeopt.Limits(max_velocity=3, max_acceleration=2, max_jerk=jerk)
        out.append(({"path": index, "max_jerk": jerk, "K": K, "length_m": curve.arc_length()},
                    timeopt.TemporalProblem(curve, limits, K=K)))
    return out


def main():
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("scheduler", nargs="?", help="a Dask scheduler's address; default: a LocalCluster here")
    parser.add_argument("--paths", type=int, default=20)
    parser.add_argument("--workers", type=int, default=2, help="the LocalCluster's worker processes")
    parser.add_argument("-o", "--output", default="batch_study.csv")
    args = parser.parse_args()

    rows = study(args.paths)
    if args.scheduler:
        client, cluster = Client(args.scheduler), None
    else:
        cluster = LocalCluster(n_workers=args.workers, threads_per_worker=1, processes=True, dashboard_address=None)
        client = Client(cluster)
    try:
        start = time.perf_counter()
        results = timeopt.solve_many([problem for _, problem in rows], client=client, progress=True)
        seconds = time.perf_counter() - start
    finally:
        client.close()
        if cluster is not None:
            cluster.close()

    with open(args.output, "w", newline="") as f:
        writer = csv.writer(f)
        writer.writerow(["path", "length_m", "max_jerk", "K", "status", "T_s", "max_jerk_ratio", "solve_ms", "message"])
        for (parameters, _), result in zip(rows, results):
            ok = result.is_success()
            writer.writerow([parameters["path"], f"{parameters['length_m']:.3f}", parameters["max_jerk"], parameters["K"],
                             result.status.name, f"{result.total_time:.6f}" if ok else "",
                             f"{result.max_jerk_ratio:.6f}" if ok else "", f"{1e3 * result.solve_time_seconds:.3f}",
                             "" if ok else result.message])
    failed = sum(not r.is_success() for r in results)
    print(f"{len(rows)} problems in {seconds:.2f} s on {len(client.nthreads()) if cluster is None else args.workers} "
          f"worker(s); {failed} not optimal; wrote {args.output}")


if __name__ == "__main__":
    main()
