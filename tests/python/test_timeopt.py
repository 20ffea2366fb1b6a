"""The Python module against independent truths: closed forms, the C++ command line on the same
files (bit for bit), brute force, finite differences and known optima. Run by ctest
(python.pytest) with PYTHONPATH=build/python, TIMEOPT_CLI and TIMEOPT_SOURCE_DIR set."""

import json
import math
import os
import subprocess
import threading

import numpy as np
import pytest
import scipy.sparse

import timeopt

SOURCE = os.environ.get("TIMEOPT_SOURCE_DIR", os.path.join(os.path.dirname(__file__), "..", ".."))
CLI = os.environ.get("TIMEOPT_CLI", os.path.join(SOURCE, "build", "timeopt"))
LINE = os.path.join(SOURCE, "examples", "line_problem.json")
FOREST = os.path.join(SOURCE, "maps", "forest_20x20.bt")


def cli_json(*args):
    """The JSON a `timeopt` command writes to stdout."""
    run = subprocess.run([CLI, *args], capture_output=True, text=True, check=True, cwd=SOURCE)
    return json.loads(run.stdout)


def test_contract_line_is_seven_seconds():
    # 10 m, vmax 2, amax 1, rest to rest: accelerate 2 s, cruise 3 s, brake 2 s. The paper's rows
    # are exact on a line (constant tangent), so T is the closed form to the solver's 1e-8.
    problem = timeopt.load_problem(LINE)
    result = timeopt.solve(problem)
    assert result.status == timeopt.TemporalStatus.optimal
    assert result.total_time == pytest.approx(7.0, rel=1e-8)
    assert result.piece_durations.shape == (1,)
    assert result.max_velocity_ratio <= 1 + 1e-8


@pytest.mark.parametrize("solver", ["socp", "ipopt"])
def test_same_t_as_the_command_line_bit_for_bit(solver, tmp_path):
    # The same problem file through the same library: for our solver not a tolerance but the same
    # double. Ipopt factorizes with MUMPS over Debian's ATLAS, whose dense kernels pick their code
    # path by the alignment of their buffers: two processes may differ in the last bits (seen on a
    # fresh machine: 2.9e-14 relative), hence 1e-12 there.
    def same(t, expected):
        return t == expected if solver == "socp" else t == pytest.approx(expected, rel=1e-12)

    result = timeopt.solve(timeopt.load_problem(LINE), solver=solver)
    assert same(result.total_time, cli_json("temporal", "--solver", solver, LINE)["total_time"])
    # The shipped waypoints, minimum-jerk, jerk-limited and certified (the README's main job):
    # the command writes its curve and result; the module solves that curve with the same limits.
    out = tmp_path / "wp"
    subprocess.run([CLI, "waypoints", os.path.join(SOURCE, "examples", "waypoints.csv"), "--kind", "minjerk",
                    "--max-velocity", "2", "--max-acceleration", "2", "--max-jerk", "10", "-K", "50",
                    "--constraint-mode", "certified", "--solver", solver, "--out-dir", str(out)],
                   check=True, capture_output=True, cwd=SOURCE)
    expected = json.loads((out / "result.json").read_text())
    curve = timeopt.Curve.load(str(out / "curve.json"))
    limits = timeopt.Limits(max_velocity=2, max_acceleration=2, max_jerk=10)
    problem = timeopt.TemporalProblem(curve, limits, K=50, constraint_mode="certified")
    assert same(timeopt.solve(problem, solver=solver).total_time, expected["total_time"])


def test_defaults_are_the_planners_flyable_ones():
    # Limits() and TemporalProblem(curve) default to what `timeopt plan` and `timeopt waypoints` use
    # (2 m/s, 2 m/s^2, 10 m/s^3, certified rows), so a default solve is the CLI's default answer to
    # the bit, and it holds every limit on the dense check (certified rows: to the solver's 1e-6).
    limits = timeopt.Limits()
    np.testing.assert_array_equal(limits.max_velocity, [2, 2, 2])
    np.testing.assert_array_equal(limits.max_acceleration, [2, 2, 2])
    np.testing.assert_array_equal(limits.max_jerk, [10, 10, 10])
    assert timeopt.Limits(max_jerk=None).max_jerk is None
    waypoints = np.loadtxt(os.path.join(SOURCE, "examples", "waypoints.csv"), delimiter=",", skiprows=1)
    problem = timeopt.TemporalProblem(timeopt.Curve.from_waypoints(waypoints))
    assert problem.constraint_mode == timeopt.ConstraintMode.certified
    result = timeopt.solve(problem)
    assert result.status == timeopt.TemporalStatus.optimal
    for ratio in (result.max_velocity_ratio, result.max_acceleration_ratio, result.max_jerk_ratio):
        assert ratio <= 1 + 1e-6


def test_a_coincident_waypoint_is_dropped():
    # The same point twice (or 1e-9 m apart) is one waypoint: the curve is that of the distinct
    # ones, the straight line here (length 2 m, against 2.35 m when the spline looped around it).
    repeated = np.array([[0, 0, 0], [1, 0, 0], [1 + 1e-9, 0, 0], [2, 0, 0]], dtype=float)
    curve = timeopt.Curve.from_waypoints(repeated)
    assert curve.num_pieces == 2
    distinct = timeopt.Curve.from_waypoints(repeated[[0, 1, 3]])
    np.testing.assert_array_equal(curve.pieces[0], distinct.pieces[0])
    assert abs(curve.arc_length() - 2.0) < 1e-9
    with pytest.raises(ValueError, match="all 3 waypoints coincide"):
        timeopt.Curve.from_waypoints(np.ones((3, 3)))


def test_curve_evaluation_matches_the_coefficients_and_finite_differences():
    waypoints = np.array([[0, 0, 1], [3, 1, 1.5], [5, -2, 1], [8, 0, 2]], dtype=float)
    curve = timeopt.Curve.from_waypoints(waypoints, kind="minjerk")
    assert curve.num_pieces == 3
    sigma = np.linspace(0, 3, 301)
    p = curve.evaluate(sigma)
    assert p.shape == (301, 3)
    np.testing.assert_allclose(p[[0, 100, 200, 300]], waypoints, atol=1e-12)
    # Piece 1 from its coefficients, by hand (Horner in numpy).
    c = curve.pieces[1]
    s = 0.37
    np.testing.assert_allclose(curve.evaluate([1 + s])[0], c @ (s ** np.arange(c.shape[1])), rtol=1e-14, atol=1e-12)
    # Derivatives against central differences (step 1e-5: error ~1e-10 of the scale, O(h^2)).
    h = 1e-5
    inner = np.array([0.3, 1.5, 2.7])
    fd = (curve.evaluate(inner + h) - curve.evaluate(inner - h)) / (2 * h)
    np.testing.assert_allclose(curve.evaluate(inner, derivative=1), fd, rtol=1e-7, atol=1e-7)


def test_trajectory_samples_start_at_rest_and_hold_the_limits():
    problem = timeopt.load_problem(LINE)
    result = timeopt.solve(problem)
    trajectory = timeopt.Trajectory(problem.curve, result)
    assert trajectory.duration == result.total_time
    ts = np.linspace(0, trajectory.duration, 701)
    p, v, a, j = trajectory.sample(ts)
    assert p.shape == v.shape == a.shape == j.shape == (701, 3)
    np.testing.assert_allclose(p[0], [0, 0, 0], atol=1e-12)
    np.testing.assert_allclose(p[-1], [10, 0, 0], atol=1e-9)
    assert np.all(np.abs(v[:, 0]) <= 2 * (1 + 1e-8)) and np.all(np.abs(a[:, 0]) <= 1 * (1 + 1e-8))
    # Cruise at 2 m/s in the middle (the closed form: t in [2, 5]).
    assert v[350, 0] == pytest.approx(2.0, rel=1e-6)


def test_limits_keywords_are_a_limits_object_of_the_files():
    # The keywords go through the reader of the files' "limits" object (one key set, one reader):
    # the shipped planner configuration's limits, every key with its value or null, are keywords
    # as they stand, and read back to the same values; a value the files refuse is refused, naming
    # the key.
    with open(os.path.join(SOURCE, "examples", "planner_config.json")) as f:
        written = json.load(f)["limits"]
    assert len(written) == 10
    limits = timeopt.Limits(**written)
    for key, value in written.items():
        got = getattr(limits, key)
        if value is None:
            assert got is None, key
        else:
            assert np.allclose(got, value, rtol=0, atol=0), key
    assert "max_acceleration_change" not in repr(limits)
    assert repr(timeopt.Limits(max_acceleration_change=5)).endswith("max_acceleration_change=5)")
    with pytest.raises(ValueError, match="Limits.max_speed: expected a finite number"):
        timeopt.Limits(max_speed=math.inf)
    with pytest.raises(ValueError, match="Limits.max_tilt: expected a number"):
        timeopt.Limits(max_tilt=[0.1, 0.2, 0.3])
    # The attributes are set through the same reader.
    limits.max_acceleration_change = 5
    assert limits.max_acceleration_change == 5
    with pytest.raises(ValueError, match="Limits.gravity: expected a finite number"):
        limits.gravity = math.nan
    with pytest.raises(ValueError, match="Limits.gravity: expected a number, got None"):
        limits.gravity = None


def test_bad_shapes_and_types_are_clear_exceptions():
    with pytest.raises(ValueError, match=r"max_velocity: expected 3 values or one, got shape \(2,\)"):
        timeopt.Limits(max_velocity=[1.0, 2.0])
    with pytest.raises(ValueError, match=r"waypoints: expected an \(N, 3\) array, got shape \(4, 2\)"):
        timeopt.Curve.from_waypoints(np.zeros((4, 2)))
    with pytest.raises(ValueError, match=r"pieces\[0\]: expected a \(3, degree \+ 1\) array"):
        timeopt.Curve([np.zeros((2, 3))])
    with pytest.raises(ValueError, match="max_jerk: expected an array of numbers"):
        timeopt.Limits(max_jerk="fast")
    with pytest.raises(ValueError, match="solver: expected 'socp' or 'ipopt'"):
        timeopt.solve(timeopt.load_problem(LINE), solver="mosek")
    with pytest.raises(TypeError, match="unknown keyword 'max_velocty'"):
        timeopt.Limits(max_velocty=2)
    # The library's own validation, with its message naming the field.
    problem = timeopt.load_problem(LINE)
    problem.limits = timeopt.Limits(max_velocity=-1)
    result = timeopt.solve(problem)
    assert result.status == timeopt.TemporalStatus.invalid_input
    assert "limits.max_velocity[0]" in result.message
    with pytest.raises(ValueError, match="limits.max_velocity"):
        problem.validate()
    with pytest.raises(OSError, match="cannot open"):
        timeopt.load_problem(os.path.join(SOURCE, "does_not_exist.json"))
    with pytest.raises(ValueError, match="K"):
        timeopt.parse_problem('{"curve": {"pieces": [{"x": [0, 1], "y": [0, 0], "z": [0, 0]}]}, '
                              '"limits": {"max_velocity": 2, "max_acceleration": 1}, "discretization": {"K": 2.5}}')
    # K: an integer in [1, 100000], else ValueError (in the constructor, the attribute and plan's keyword).
    curve = timeopt.load_problem(LINE).curve
    for bad in (2.5, "a", None, float("nan"), True, -1, 0, 100001, 10**20):
        with pytest.raises(ValueError, match=r"K: expected an integer in \[1, 100000\]"):
            timeopt.TemporalProblem(curve, K=bad)
        with pytest.raises(ValueError, match=r"K: expected an integer in \[1, 100000\]"):
            problem.K = bad
    with pytest.raises(ValueError, match=r"K: expected an integer"):
        timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5], K=2.5)
    # A memory budget below the solve's estimated peak (64 MiB for the process alone): ValueError.
    with pytest.raises(ValueError, match="max_memory_mb: the problem's 1 x 50 cells need about"):
        timeopt.solve(timeopt.load_problem(LINE), max_memory_mb=1)
    with pytest.raises(ValueError, match="max_memory_mb: expected a number >= 0"):
        timeopt.solve(timeopt.load_problem(LINE), max_memory_mb=-1)
    assert timeopt.solve(timeopt.load_problem(LINE), max_memory_mb=1000).status == timeopt.TemporalStatus.optimal
    # A reusable Solver holds each solve to its budget the same way, and still solves after a refusal.
    for name in ("socp", "ipopt"):
        budgeted = timeopt.Solver(name, max_memory_mb=1)
        with pytest.raises(ValueError, match="max_memory_mb: the problem's 1 x 50 cells need about .* with " + name):
            budgeted.solve(timeopt.load_problem(LINE))
        roomy = timeopt.Solver(name, max_memory_mb=1000)
        assert roomy.solve(timeopt.load_problem(LINE)).status == timeopt.TemporalStatus.optimal
    with pytest.raises(ValueError, match="max_memory_mb: expected a number >= 0"):
        timeopt.Solver("socp", max_memory_mb=float("nan"))
    problem.K = np.int64(40)
    assert problem.K == 40 and timeopt.TemporalProblem(curve, K=7).K == 7
    # float32 and integer input are converted, not refused.
    limits = timeopt.Limits(max_velocity=np.array([1, 2, 3], dtype=np.int32), max_acceleration=np.float32(1.5))
    np.testing.assert_array_equal(limits.max_velocity, [1.0, 2.0, 3.0])
    assert limits.max_velocity.dtype == np.float64


def test_infeasible_is_a_status_with_a_diagnosis():
    problem = timeopt.load_problem(LINE)
    problem.start_velocity = [3.0, 0.0, 0.0]  # above vmax = 2 at the start
    result = timeopt.solve(problem)
    assert result.status == timeopt.TemporalStatus.infeasible
    assert result.infeasibility["cause"] == "boundary_speed"
    with pytest.raises(ValueError, match="not optimal"):
        timeopt.Trajectory(problem.curve, result)
    assert result.boundary_relaxation is None
    # Relaxed: the start speed lowered to the limit (2 m/s), the contract line then takes 6 s.
    problem.relax_boundary = True
    relaxed = timeopt.solve(problem)
    assert relaxed.status == timeopt.TemporalStatus.optimal
    assert relaxed.boundary_relaxation["start_speed_given"] == pytest.approx(3.0)
    assert relaxed.boundary_relaxation["start_speed"] == pytest.approx(2.0, rel=1e-6)
    assert relaxed.boundary_relaxation["start_scale"] == pytest.approx(2.0 / 3.0, rel=1e-6)
    assert relaxed.boundary_relaxation["start_acceleration"] == "unchanged"
    assert relaxed.total_time == pytest.approx(6.0, rel=1e-6)


def test_conic_solver_on_known_optima():
    # max x + y on the unit disc: (1, x, y) in the second-order cone of size 3; optimum -sqrt(2).
    G = scipy.sparse.csc_matrix(np.array([[0.0, 0.0], [-1.0, 0.0], [0.0, -1.0]]))
    r = timeopt.conic.solve(c=[-1.0, -1.0], G=G, h=[1.0, 0.0, 0.0], cones={"q": [3]})
    assert r.status == timeopt.conic.Status.optimal
    assert r.primal_objective == pytest.approx(-math.sqrt(2), rel=1e-7)
    np.testing.assert_allclose(r.x, [1 / math.sqrt(2)] * 2, rtol=1e-6)
    # An LP with an equality, dense matrices: min x0 + 2 x1, x0 + x1 = 1, x >= 0 -> x = (1, 0).
    r = timeopt.conic.solve(c=[1.0, 2.0], G=-np.eye(2), h=[0.0, 0.0], A=[[1.0, 1.0]], b=[1.0], cones={"l": 2})
    assert r.primal_objective == pytest.approx(1.0, abs=1e-7)
    # Infeasible: x >= 1 and x <= 0.
    r = timeopt.conic.solve(c=[1.0], G=np.array([[-1.0], [1.0]]), h=[-1.0, 0.0], cones={"l": 2})
    assert r.status == timeopt.conic.Status.primal_infeasible
    with pytest.raises(ValueError):
        timeopt.conic.solve(c=[1.0], G=np.eye(2), h=[0.0, 0.0], cones={"l": 2})  # G has 2 columns, c 1


def test_cbf_round_trip(tmp_path):
    G = scipy.sparse.csc_matrix(np.array([[0.0, 0.0], [-1.0, 0.0], [0.0, -1.0]]))
    path = str(tmp_path / "disc.cbf")
    timeopt.conic.write_cbf(path, c=[-1.0, -1.0], G=G, h=[1.0, 0.0, 0.0], cones={"q": [3]})
    model = timeopt.conic.read_cbf(path)
    assert model["cones"] == {"l": 0, "q": [3], "r": []}
    assert (model["G"] != G).nnz == 0
    r = timeopt.conic.solve(model["c"], model["G"], model["h"], model["A"], model["b"], model["cones"])
    assert r.primal_objective == pytest.approx(-math.sqrt(2), rel=1e-7)


def test_esdf_queries_match_brute_force_on_the_shipped_map():
    occupancy = timeopt.OccupancyMap.load(os.path.join(SOURCE, "maps", "boxes_20x20.bt"))
    esdf = timeopt.Esdf.from_map(occupancy)
    r = esdf.resolution
    low, high = esdf.domain
    axes = [np.arange(low[k], high[k] + r / 2, r) for k in range(3)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    occupied = occupancy.is_occupied(centres)
    assert occupied.any() and not occupied.all()
    obstacles = centres[occupied]
    rng = np.random.default_rng(7)
    free = centres[~occupied]
    picks = free[rng.choice(len(free), 40, replace=False)]
    # The definition (esdf.h): at a free centre, min over occupied centres |c - o| - r/2. Stored
    # as float: 6e-8 relative, so 1e-5 m on these 20 m maps.
    truth = np.array([np.min(np.linalg.norm(obstacles - c, axis=1)) - r / 2 for c in picks])
    np.testing.assert_allclose(esdf.distance(picks), truth, atol=1e-5)
    # Gradients against central differences of the field itself, inside interpolation cells.
    points = picks + r * 0.31
    d, g = esdf.distance_and_gradient(points)
    np.testing.assert_allclose(d, esdf.distance(points), atol=1e-12)
    h = 1e-6
    for axis in range(3):
        step = np.zeros(3)
        step[axis] = h
        fd = (esdf.distance(points + step) - esdf.distance(points - step)) / (2 * h)
        np.testing.assert_allclose(g[:, axis], fd, atol=1e-4)
    with pytest.raises(ValueError, match=r"points: expected an \(N, 3\) array"):
        esdf.distance(np.zeros((5, 2)))
    # The memory budget: this field needs 9 bytes per voxel; 0.01 MB is refused before allocating.
    with pytest.raises(ValueError, match="above the memory budget"):
        timeopt.Esdf.from_map(occupancy, max_memory_mb=0.01)


def test_plan_on_the_shipped_forest_matches_the_command_line(tmp_path):
    plan = timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5])
    assert plan.status == timeopt.PlanStatus.success, plan.message
    summary = cli_json("plan", "--output", str(tmp_path / "plan.csv"), "--plot", str(tmp_path / "plan.png"))
    assert plan.total_time == summary["total_time"]
    summary_py = plan.summary()
    assert summary_py == json.loads(plan.to_json())
    assert summary_py["total_time"] == plan.total_time
    trajectory = plan.trajectory()
    report = timeopt.simulate(trajectory, timeopt.Limits(max_velocity=2, max_acceleration=2, max_jerk=10))
    # The README's main job: flown within 1% of the limits (1.0043 amax measured).
    assert report.max_acceleration_ratio < 1.01 and report.max_velocity_ratio < 1.01
    # Clearance: every sampled point at least the robot radius (0.3 m) from the obstacles.
    esdf = timeopt.Esdf.from_map(timeopt.OccupancyMap.load(FOREST))
    p, _, _, _ = trajectory.sample(np.linspace(0, trajectory.duration, 400))
    assert esdf.distance(p).min() >= 0.3 - 1e-6


def test_solves_from_threads_agree():
    # The GIL is released during solves: four threads solve at once and get the serial answer.
    problem = timeopt.load_problem(LINE)
    serial = timeopt.solve(problem).total_time
    answers = []

    def work():
        solver = timeopt.Solver("socp")
        for _ in range(20):
            answers.append(solver.solve(problem).total_time)

    threads = [threading.Thread(target=work) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len(answers) == 80 and all(t == serial for t in answers)


def rss_bytes():
    with open("/proc/self/statm") as f:
        return int(f.read().split()[1]) * os.sysconf("SC_PAGE_SIZE")


def test_no_leak_over_ten_thousand_solves():
    # Every result, profile and array handed to Python must be freed: RSS after 10,000 solves of
    # a small problem (K = 10) within 8 MB of RSS after the first 500 (allocator slack; a leak of
    # one result's arrays per solve would be tens of MB).
    problem = timeopt.load_problem(LINE)
    problem.K = 10
    for _ in range(500):
        result = timeopt.solve(problem)
        _ = result.piece_durations, result.profile.b
    before = rss_bytes()
    for _ in range(10000):
        result = timeopt.solve(problem)
        _ = result.piece_durations, result.profile.b
    assert rss_bytes() - before < 8 * 1024 * 1024


def test_the_type_stub_names_every_public_attribute():
    # python/timeopt.pyi must not fall behind the module: every public name of the module and of
    # its conic submodule is declared there (classes, functions, enums).
    import ast

    tree = ast.parse(open(os.path.join(SOURCE, "python", "timeopt.pyi")).read())
    top = {node.name for node in tree.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    conic_class = next(node for node in tree.body if isinstance(node, ast.ClassDef) and node.name == "conic")
    in_conic = {node.name for node in conic_class.body if isinstance(node, (ast.ClassDef, ast.FunctionDef))}
    public = {name for name in dir(timeopt) if not name.startswith("_")}
    assert public - top == set()
    assert {name for name in dir(timeopt.conic) if not name.startswith("_")} - in_conic == set()


def test_one_flight_verdict_for_the_shipped_waypoints(tmp_path):
    # The same jerk-limited trajectory judged three ways: `timeopt waypoints` (its result.json's
    # flight block), Python's simulate on the same curve and limits, and `timeopt simulate --samples`
    # on the 100 Hz samples the command wrote (a C2 interpolation of them). All three use the
    # product's flight criterion (1%: the simulated controller holds its jerk over each 1 ms step)
    # and all three say the limits hold; a tolerance given explicitly is the one reported.
    out = tmp_path / "wp"
    subprocess.run([CLI, "waypoints", os.path.join(SOURCE, "examples", "waypoints.csv"), "--out-dir", str(out)],
                   check=True, capture_output=True, cwd=SOURCE)
    flight = json.loads((out / "result.json").read_text())["flight"]
    assert flight["feasible"] and flight["tolerance"] == 0.01
    curve = timeopt.Curve.load(str(out / "curve.json"))
    limits = timeopt.Limits()
    result = timeopt.solve(timeopt.TemporalProblem(curve, limits))
    report = timeopt.simulate(timeopt.Trajectory(curve, result), limits)
    assert report.feasible and report.tolerance == 0.01
    # The same solve in another process: equal to the last bits but for buffer alignment (1e-12).
    assert report.max_acceleration_ratio == pytest.approx(flight["max_acceleration_ratio"], rel=1e-9)
    assert timeopt.simulate(timeopt.Trajectory(curve, result), limits, tolerance=1e-9).tolerance == 1e-9
    sampled = subprocess.run([CLI, "simulate", "--samples", str(out / "samples.csv"), "--max-velocity", "2",
                              "--max-acceleration", "2"], capture_output=True, text=True, cwd=SOURCE)
    assert sampled.returncode == 0, sampled.stdout + sampled.stderr
    sampled_report = json.loads(sampled.stdout)
    assert sampled_report["feasible"] and sampled_report["tolerance"] == 0.01
    assert sampled_report["max_acceleration_ratio"] <= 1.01


def test_version_and_reprs():
    # The version is the C++ library's (CMake's project version, also `timeopt --version`).
    version = subprocess.run([CLI, "--version"], capture_output=True, text=True, check=True).stdout
    assert timeopt.__version__ in version
    assert repr(timeopt.Limits()) == "Limits(max_velocity=[2, 2, 2], max_acceleration=[2, 2, 2], max_jerk=[10, 10, 10])"
    assert repr(timeopt.Limits(max_jerk=None, max_speed=3)).endswith("max_jerk=None, max_speed=3)")


@pytest.mark.parametrize("solver", ["socp", "ipopt"])
def test_one_solver_shared_by_threads_gives_the_sequential_answers(solver):
    # A Solver serializes its own solves, so threads sharing one get exactly what one thread gets
    # (it kept workspaces between solves that two threads once overwrote at the same time).
    rng = np.random.default_rng(3)
    problems = []
    for _ in range(6):
        waypoints = np.cumsum(rng.uniform(-3, 3, size=(5, 3)) * [1, 1, 0.3], axis=0)
        problems.append(timeopt.TemporalProblem(timeopt.Curve.from_waypoints(waypoints), K=20))
    expected = [timeopt.Solver(solver).solve(p).total_time for p in problems]
    shared = timeopt.Solver(solver)
    got = [None] * (4 * len(problems))

    def work(k):
        got[k] = shared.solve(problems[k % len(problems)]).total_time

    threads = [threading.Thread(target=work, args=(k,)) for k in range(len(got))]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    # Another process or buffer alignment may change the last bits with Ipopt (see above).
    assert got == pytest.approx([expected[k % len(problems)] for k in range(len(got))], rel=1e-12)


def test_trajectory_file_and_exports_match_the_command_line(tmp_path):
    # The waypoints command writes trajectory.json; Python reads it back and gives the same samples
    # to the bit as its samples.csv (the file is exact), saves it again byte for byte, and its
    # exports are the command's own files, byte for byte.
    out = tmp_path / "wp"
    subprocess.run([CLI, "waypoints", os.path.join(SOURCE, "examples", "waypoints.csv"), "--out-dir", str(out), "-q"],
                   check=True, capture_output=True, cwd=SOURCE)
    trajectory = timeopt.Trajectory.load(str(out / "trajectory.json"))
    samples = np.loadtxt(out / "samples.csv", delimiter=",", skiprows=1)
    ts, (p, v, a, j) = trajectory.sample_rate(100.0)
    assert np.array_equal(ts, samples[:, 0])
    assert np.array_equal(p, samples[:, 1:4]) and np.array_equal(v, samples[:, 4:7])
    trajectory.save(str(tmp_path / "again.json"))
    assert (tmp_path / "again.json").read_text() == (out / "trajectory.json").read_text()
    for fmt in ("csv", "px4", "polynomial"):
        mine, theirs = tmp_path / ("py." + fmt), tmp_path / ("cli." + fmt)
        timeopt.export(trajectory, fmt, str(mine), yaw="goal", max_yaw_rate=0.5)
        subprocess.run([CLI, "export", str(out / "trajectory.json"), "--format", fmt, "-o", str(theirs),
                        "--yaw", "goal", "--max-yaw-rate", "0.5"], check=True)
        assert mine.read_bytes() == theirs.read_bytes(), fmt
    # The heading: rate-limited, its rate the finite difference of the yaw.
    yaw, rate = trajectory.yaw(ts, yaw="velocity", max_yaw_rate=0.5)
    assert np.all(np.abs(rate) <= 0.5)
    assert np.allclose(np.diff(yaw) / np.diff(ts), rate[:-1], atol=1e-6)
    with pytest.raises(ValueError, match="yaw"):
        trajectory.yaw(ts, yaw="north")
    with pytest.raises(ValueError, match="format"):
        timeopt.export(trajectory, "kml", str(tmp_path / "x"))


def test_plan_and_trajectory_pages(tmp_path):
    # The 3D page from Python: one file holding the inlined libraries and the samples at 50 Hz
    # (its readiness in a browser is tests/viz/check_plan_page.py's).
    forest = timeopt.OccupancyMap.load(FOREST)
    plan = timeopt.plan(FOREST, [1, 1, 1.5], [19, 19, 1.5])
    assert plan.is_success()
    page = tmp_path / "plan.html"
    plan.to_html(str(page), map=forest)
    text = page.read_text()
    assert "REVISION=\"111\"" in text and "Chart.js v3" in text      # inlined, no network
    assert 'data-ready="false"' in text and len(text) < 15 << 20
    ts, _ = plan.trajectory().sample_rate(50.0)
    assert '"t": [' in text and text.count(",", text.index('"t": ['), text.index("]", text.index('"t": ['))) == len(ts) - 1
    plan.trajectory().to_html(str(tmp_path / "t.html"), limits=timeopt.Limits())
    assert (tmp_path / "t.html").stat().st_size > 1e6
    with pytest.raises(ValueError):
        timeopt.plan(FOREST, [1, 1, 1.5], [1, 1, 1.5]).to_html(str(tmp_path / "x.html"))
