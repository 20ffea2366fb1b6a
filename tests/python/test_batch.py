"""timeopt.solve_many / plan_many and pickling, against the truth of a plain loop of
timeopt.solve / timeopt.plan in this process (bit for bit), on threads and on a two-process Dask
LocalCluster (Debian's python3-distributed; those tests skip, saying why, without it)."""

import csv
import importlib.util
import json
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

import timeopt

SOURCE = os.environ.get("TIMEOPT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
FOREST = os.path.join(SOURCE, "maps", "forest_20x20.bt")
HAS_DASK = importlib.util.find_spec("distributed") is not None
needs_dask = pytest.mark.skipif(not HAS_DASK, reason="dask.distributed is missing (Debian: python3-distributed)")


def problems(count, mode, jerk, seed=1):
    """Random minimum-jerk curves through 5 waypoints, K = 20 (small, so that a batch is quick)."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        waypoints = np.cumsum(rng.uniform(-4, 4, size=(5, 3)) * [1, 1, 0.3], axis=0)
        curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
        limits = timeopt.Limits(max_velocity=3, max_acceleration=2, max_jerk=10 if jerk else None)
        out.append(timeopt.TemporalProblem(curve, limits, K=20, constraint_mode=mode))
    return out


def same(a, b):
    """Two TemporalResults equal to the bit: status, T, the profile's values and the JSON."""
    if a.status != b.status or a.message != b.message:
        return False
    if not a.is_success():
        return True
    return (a.total_time == b.total_time and np.array_equal(a.profile.b, b.profile.b)
            and np.array_equal(a.piece_durations, b.piece_durations) and answer(a) == answer(b))


def answer(result):
    """A result's JSON without its timings (which differ from run to run)."""
    fields = json.loads(result.to_json())
    for key in ("build_time_ms", "solve_time_ms"):
        fields.pop(key, None)
    return fields


def attributes(obj):
    """Every public attribute of a module object that is not a method, as comparable values."""
    out = {}
    for name in dir(obj):
        if name.startswith("_"):
            continue
        value = getattr(obj, name)
        if callable(value) and not isinstance(value, (timeopt.Curve, timeopt.TemporalProfile)):
            continue
        out[name] = value
    return out


def assert_same_attributes(a, b):
    left, right = attributes(a), attributes(b)
    assert left.keys() == right.keys()
    for name, value in left.items():
        other = right[name]
        if isinstance(value, np.ndarray):
            assert np.array_equal(value, other, equal_nan=True), name
        elif isinstance(value, timeopt.Curve):
            assert [p.tolist() for p in value.pieces] == [p.tolist() for p in other.pieces], name
        elif isinstance(value, timeopt.TemporalProfile):
            assert value.jerk_limited == other.jerk_limited and value.K == other.K, name
            assert np.array_equal(value.b, other.b), name
        elif isinstance(value, (timeopt.Limits, timeopt.TemporalResult)):
            assert_same_attributes(value, other)
        elif isinstance(value, float) and np.isnan(value):
            assert np.isnan(other), name
        else:
            assert value == other, name


@pytest.mark.parametrize("mode,jerk", [("certified", True), ("paper", False), ("certified", False)])
def test_pickled_problems_and_results_are_the_same_objects(mode, jerk):
    problem = problems(1, mode, jerk)[0]
    problem.limits.max_speed = 2.5  # an optional limit, and a ratio for it in the result
    problem.rho = 0.0 if jerk else 1e-3
    copy = pickle.loads(pickle.dumps(problem))
    assert_same_attributes(problem, copy)
    result = timeopt.solve(problem)
    assert result.is_success(), result.message
    again = pickle.loads(pickle.dumps(result))
    assert_same_attributes(result, again)
    assert same(result, again)
    # The copy solves to the same answer, bit for bit: nothing of the problem was lost.
    assert same(timeopt.solve(copy), result)
    # A trajectory samples the same after the round trip.
    trajectory = timeopt.Trajectory(problem.curve, result)
    ts = np.linspace(0, trajectory.duration, 97)
    for x, y in zip(trajectory.sample(ts), pickle.loads(pickle.dumps(trajectory)).sample(ts)):
        assert np.array_equal(x, y)


def test_results_without_an_answer_and_plans_pickle():
    failed = timeopt.solve_many(["not a problem"], threads=1)[0]
    assert failed.status == timeopt.TemporalStatus.invalid_input
    assert_same_attributes(failed, pickle.loads(pickle.dumps(failed)))
    # An infeasible start (too fast for the first bend): a result with its diagnosis.
    line = timeopt.TemporalProblem(timeopt.Curve([np.array([[0.0, 1.0], [0.0, 0.0], [0.0, 0.0]])]),
                                   timeopt.Limits(max_velocity=2, max_acceleration=1, max_jerk=None),
                                   K=10, constraint_mode="paper", start_velocity=[5.0, 0.0, 0.0])
    infeasible = timeopt.solve(line)
    assert infeasible.status == timeopt.TemporalStatus.infeasible and infeasible.infeasibility is not None
    assert_same_attributes(infeasible, pickle.loads(pickle.dumps(infeasible)))
    plan = timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5])
    assert plan.is_success(), plan.message
    copy = pickle.loads(pickle.dumps(plan))
    assert_same_attributes(plan, copy)
    assert copy.to_json() == plan.to_json()
    assert same(copy.temporal, plan.temporal)


def test_a_state_of_another_kind_or_version_is_refused():
    state = problems(1, "paper", False)[0].__getstate__()
    with pytest.raises(ValueError, match="state version 99"):
        timeopt.TemporalProblem.__new__(timeopt.TemporalProblem).__setstate__(("TemporalProblem", 99) + tuple(state[2:]))
    with pytest.raises(ValueError, match="not a timeopt Limits state"):
        timeopt.Limits.__new__(timeopt.Limits).__setstate__(state)


@pytest.mark.parametrize("mode,jerk", [("certified", True), ("certified", False)])
def test_threads_give_the_loops_answers_in_order(mode, jerk):
    batch = problems(24, mode, jerk)
    loop = [timeopt.solve(p) for p in batch]
    assert all(r.is_success() for r in loop)
    for threads in (1, 2, 5):
        many = timeopt.solve_many(batch, threads=threads)
        assert len(many) == len(batch)
        assert all(same(a, b) for a, b in zip(loop, many))


def test_a_failing_problem_comes_back_with_its_status_in_place():
    batch = problems(6, "certified", True)
    budgeted = timeopt.solve_many(batch[:2], threads=2, max_memory_mb=0.001)
    assert all(r.status == timeopt.TemporalStatus.invalid_input and "memory budget" in r.message for r in budgeted)
    mixed = batch[:3] + [None, "x"] + batch[3:]
    done = []
    many = timeopt.solve_many(mixed, threads=2, progress=lambda n, total: done.append((n, total)))
    assert [r.status == timeopt.TemporalStatus.invalid_input for r in many] == [False] * 3 + [True, True] + [False] * 3
    assert "TypeError" in many[3].message
    assert all(same(timeopt.solve(p), r) for p, r in zip(batch, many[:3] + many[5:]))
    assert done[-1] == (8, 8) and [n for n, _ in done] == sorted(n for n, _ in done)
    with pytest.raises(ValueError, match="threads"):
        timeopt.solve_many(batch, threads=0)
    with pytest.raises(ValueError, match="solver"):
        timeopt.solve_many(batch, solver="mosek")
    assert timeopt.solve_many([], threads=2) == []


def test_plans_on_threads_equal_the_loop_and_a_bad_query_is_a_status():
    queries = [(FOREST, [1, 1, 1.5], [19, 19, 1.5]), {"map": FOREST, "start": [2, 18, 1.5], "goal": [18, 2, 1.5], "K": 10},
               {"map": os.path.join(SOURCE, "no_such_map.bt"), "start": [1, 1, 1], "goal": [2, 2, 1]},
               {"map": FOREST, "start": [1, 1, 1.5]}]
    many = timeopt.plan_many(queries, threads=2, max_jerk=10)
    loop = [timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5], max_jerk=10),
            timeopt.plan(FOREST, [2, 18, 1.5], [18, 2, 1.5], K=10, max_jerk=10)]
    for a, b in zip(loop, many[:2]):
        assert a.is_success() and a.status == b.status and a.total_time == b.total_time and same(a.temporal, b.temporal)
    assert many[2].status == timeopt.PlanStatus.invalid_input and "no_such_map" in many[2].message
    assert many[3].status == timeopt.PlanStatus.invalid_input and "'goal'" in many[3].message


@pytest.fixture(scope="module")
def dask_client():
    if not HAS_DASK:
        pytest.skip("dask.distributed is missing (Debian: python3-distributed)")
    from distributed import Client, LocalCluster

    # Worker processes import timeopt from the PYTHONPATH they inherit (ctest sets it). A machine
    # where two local worker processes cannot start (no process spawning or no localhost sockets)
    # skips these tests, saying why; everything after the start is asserted.
    try:
        cluster = LocalCluster(n_workers=2, threads_per_worker=1, processes=True, dashboard_address=None)
    except Exception as e:  # noqa: BLE001
        pytest.skip(f"a Dask LocalCluster of 2 processes cannot start here: {type(e).__name__}: {e}")
    with cluster, Client(cluster) as client:
        yield client


@needs_dask
@pytest.mark.parametrize("mode,jerk", [("certified", True), ("certified", False)])
def test_a_two_process_cluster_gives_the_loops_answers_in_order(dask_client, mode, jerk):
    batch = problems(16, mode, jerk, seed=2)
    loop = [timeopt.solve(p) for p in batch]
    many = timeopt.solve_many(batch + [None], client=dask_client)
    assert all(same(a, b) for a, b in zip(loop, many))
    assert many[-1].status == timeopt.TemporalStatus.invalid_input
    # Both workers took part: the chunks went to two processes.
    assert len(dask_client.nthreads()) == 2


@needs_dask
def test_plans_on_a_cluster_need_map_paths(dask_client):
    many = timeopt.plan_many([(FOREST, [1, 1, 1.5], [19, 19, 1.5])], client=dask_client, max_jerk=10)
    loop = timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5], max_jerk=10)
    assert many[0].total_time == loop.total_time and same(many[0].temporal, loop.temporal)
    with pytest.raises(TypeError, match="file path"):
        timeopt.plan_many([(timeopt.OccupancyMap.load(FOREST), [1, 1, 1.5], [19, 19, 1.5])], client=dask_client)


@needs_dask
def test_the_example_writes_its_study(tmp_path, dask_client):  # the fixture: a cluster can start here
    # examples/python/batch_dask.py end to end on its own LocalCluster: 2 paths x 3 jerk limits x 2 K.
    output = tmp_path / "study.csv"
    run = subprocess.run([sys.executable, os.path.join(SOURCE, "examples", "python", "batch_dask.py"), "--paths", "2",
                          "--workers", "2", "-o", str(output)], capture_output=True, text=True, timeout=300)
    assert run.returncode == 0, run.stderr[-2000:]
    with open(output) as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 12 and all(row["status"] == "optimal" for row in rows)
    # Within a path and K, a higher jerk limit never takes longer.
    for path in ("0", "1"):
        for K in ("20", "50"):
            times = [float(r["T_s"]) for r in rows if r["path"] == path and r["K"] == K]
            assert times == sorted(times, reverse=True)
