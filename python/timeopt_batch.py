"""Many problems at once: timeopt.solve_many and timeopt.plan_many, on threads or a Dask cluster.

This file is part of the module `timeopt` itself: the build embeds it, and the module runs it in
its own namespace when it is imported (so that its functions are timeopt.solve_many, ... and
pickle by name on a Dask worker that imports timeopt). The names it uses (Solver, plan,
_failed_result, _failed_plan) are the module's.

Results come back in the order of the inputs and equal, to the bit, those of a loop of
timeopt.solve / timeopt.plan: every solve is the same computation, only where it runs differs. A
problem that fails (invalid input, a memory budget, a wrong type) comes back as its result with a
status and a message; it never stops the batch.
"""

import os as _os
import sys as _sys
import threading as _threading
from concurrent.futures import ThreadPoolExecutor as _ThreadPoolExecutor
from concurrent.futures import as_completed as _as_completed


_solvers = _threading.local()


def _solver(solver, max_memory_mb):
    """This thread's Solver for (solver, max_memory_mb), kept from one batch to the next: its
    workspaces stay allocated (a fresh Solver's first solves touch new pages). One per thread, as
    Solver serializes its own solves."""
    cache = getattr(_solvers, "cache", None)
    if cache is None:
        cache = _solvers.cache = {}
    key = (solver, float(max_memory_mb))
    if key not in cache:
        cache[key] = Solver(solver, max_memory_mb)
    return cache[key]


def _solve_each(problems, solver, max_memory_mb):
    """Solves `problems` one after the other with this thread's Solver; a problem that raises
    becomes a result with status invalid_input and the error as its message."""
    s = _solver(solver, max_memory_mb)
    out = []
    for problem in problems:
        try:
            out.append(s.solve(problem))
        except Exception as e:  # noqa: BLE001 - every failure becomes that item's result
            out.append(_failed_result(solver, f"{type(e).__name__}: {e}"))
    return out


def _plan_each(queries, common):
    """Plans each query (map, start, goal, keywords); a query that raises becomes a PlanResult
    with status invalid_input and the error as its message."""
    out = []
    for query in queries:
        try:
            map_, start, goal, keywords = _query_parts(query)
            if isinstance(map_, _os.PathLike):
                map_ = _os.fspath(map_)
            out.append(plan(map_, start, goal, **{**common, **keywords}))
        except Exception as e:  # noqa: BLE001
            out.append(_failed_plan(f"{type(e).__name__}: {e}"))
    return out


def _query_parts(query):
    if isinstance(query, dict):
        keywords = dict(query)
        try:
            parts = keywords.pop("map"), keywords.pop("start"), keywords.pop("goal")
        except KeyError as e:
            raise ValueError(f"a query needs 'map', 'start' and 'goal'; {e} is missing") from None
        return (*parts, keywords)
    if isinstance(query, (tuple, list)) and len(query) == 3:
        return query[0], query[1], query[2], {}
    raise TypeError("a query is a dict with 'map', 'start', 'goal' (and plan keywords) or a tuple (map, start, goal)")


def _chunks(items, count):
    """`items` in `count` consecutive chunks of nearly equal size (none empty)."""
    count = max(1, min(count, len(items)))
    size, extra = divmod(len(items), count)
    out, start = [], 0
    for i in range(count):
        end = start + size + (1 if i < extra else 0)
        out.append(items[start:end])
        start = end
    return out


def _reporter(progress, total):
    """A function of the number done so far, from `progress`: False (nothing), True (a line on
    stderr) or a callable(done, total)."""
    if not progress:
        return lambda done: None
    if callable(progress):
        return lambda done: progress(done, total)

    def line(done):
        _sys.stderr.write(f"\rtimeopt: {done}/{total} done")
        if done == total:
            _sys.stderr.write("\n")
        _sys.stderr.flush()

    return line


def _run(function, items, extra, *, threads, client, progress, chunks_per_worker=2):
    """function(chunk, *extra) over chunks of `items`, in order, concatenated."""
    items = list(items)
    if client is None:
        if threads is None:
            threads = _os.cpu_count() or 1
        if not isinstance(threads, int) or isinstance(threads, bool) or threads < 1:
            raise ValueError(f"threads: expected a positive integer or None, got {threads!r}")
    if not items:
        return []
    report = _reporter(progress, len(items))
    if client is not None:
        return _run_dask(function, items, extra, client, report, chunks_per_worker)
    # Two chunks per thread (and per worker thread of a cluster): a slow chunk holds up half a
    # thread's share, not all of it, and few chunks keep a cluster's per-task costs small.
    chunks = _chunks(items, threads * chunks_per_worker)
    results = [None] * len(chunks)
    done = 0
    with _ThreadPoolExecutor(max_workers=threads) as pool:
        futures = {pool.submit(function, chunk, *extra): i for i, chunk in enumerate(chunks)}
        for future in _as_completed(futures):
            i = futures[future]
            results[i] = future.result()
            done += len(results[i])
            report(done)
    return [r for chunk in results for r in chunk]


def _run_dask(function, items, extra, client, report, chunks_per_worker):
    try:
        from distributed import as_completed
    except ImportError as e:  # pragma: no cover - a client implies distributed
        raise ImportError("client=: dask.distributed is not installed (Debian: python3-distributed)") from e
    workers = max(1, sum(client.nthreads().values()))
    chunks = _chunks(items, workers * chunks_per_worker)
    # Each chunk a task; pure=False: every call is its own task, even for equal chunks. A worker
    # lost mid-task has its tasks run again elsewhere by the scheduler.
    futures = [client.submit(function, chunk, *extra, pure=False) for chunk in chunks]
    index = {future.key: i for i, future in enumerate(futures)}
    results = [None] * len(chunks)
    done = 0
    for future in as_completed(futures):
        i = index[future.key]
        results[i] = future.result()
        done += len(results[i])
        report(done)
    return [r for chunk in results for r in chunk]


def solve_many(problems, *, solver="socp", threads=None, client=None, progress=False, max_memory_mb=0.0):
    """Solves many TemporalProblems; returns their TemporalResults in the same order.

    threads: the number of threads (default: the machine's cores); solves release the GIL, so they
    run in parallel. client: a dask.distributed.Client; the problems then go to its workers in
    chunks (pickled exactly) and `threads` is not used. progress: True for a line on stderr, or a
    callable(done, total). max_memory_mb > 0: each solve is held to it, as timeopt.solve's is.

    The results equal those of [timeopt.solve(p, solver) for p in problems], to the bit. A problem
    that fails comes back as its result (status invalid_input, or the solver's own status) with a
    message; it never raises or drops an item.
    """
    if solver not in ("socp", "ipopt"):
        raise ValueError(f"solver: expected 'socp' or 'ipopt', got {solver!r}")
    return _run(_solve_each, problems, (solver, max_memory_mb), threads=threads, client=client, progress=progress)


def plan_many(queries, *, threads=None, client=None, progress=False, **keywords):
    """Plans many queries; returns their PlanResults in the same order.

    Each query is a tuple (map, start, goal) or a dict {"map": ..., "start": ..., "goal": ..., and
    any timeopt.plan keyword for this query alone}; `keywords` apply to every query (a query's own
    win). A map is an Esdf, an OccupancyMap or a .bt/.ot path; with a Dask client give paths that
    every worker can read (maps are not pickled). threads, client, progress: as in solve_many.

    The results equal those of a loop of timeopt.plan, to the bit. A query that fails (a bad map
    path, a bad keyword) comes back as a PlanResult with status invalid_input and a message.
    """
    queries = list(queries)
    if client is not None:
        for i, query in enumerate(queries):
            try:
                map_ = _query_parts(query)[0]
            except (TypeError, ValueError):
                continue  # reported as that query's result
            if not isinstance(map_, (str, _os.PathLike)):
                raise TypeError(f"queries[{i}]: with a Dask client, give the map as a file path the workers can read "
                                f"(got {type(map_).__name__})")
    return _run(_plan_each, queries, (keywords,), threads=threads, client=client, progress=progress)
