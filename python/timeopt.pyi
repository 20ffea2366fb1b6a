# Type stub of the compiled module `timeopt` (python/timeopt_module.cpp, python/bind_*.cpp), for editors and type
# checkers. tests/python checks that it names every public attribute of the module.
from typing import Any, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

__version__: str

ArrayLike = npt.ArrayLike
Array = npt.NDArray[np.float64]

class FileError(OSError): ...

class TemporalStatus:
    optimal: TemporalStatus
    infeasible: TemporalStatus
    iteration_limit: TemporalStatus
    numerical_error: TemporalStatus
    invalid_input: TemporalStatus
    name: str
    value: int

class ConstraintMode:
    paper: ConstraintMode
    certified: ConstraintMode
    name: str
    value: int

class PlanStatus:
    success: PlanStatus
    name: str
    value: int
    def __getattr__(self, name: str) -> PlanStatus: ...

class Limits:
    def __init__(self, *, max_velocity: ArrayLike = ..., max_acceleration: ArrayLike = ...,
                 max_jerk: Optional[ArrayLike] = ..., max_speed: Optional[float] = ...,
                 max_acceleration_norm: Optional[float] = ..., max_thrust: Optional[float] = ...,
                 min_thrust: Optional[float] = ..., max_tilt: Optional[float] = ...,
                 max_acceleration_change: Optional[float] = ..., gravity: float = ...) -> None: ...
    max_velocity: Array
    max_acceleration: Array
    max_jerk: Optional[Array]
    max_speed: Optional[float]
    max_acceleration_norm: Optional[float]
    max_thrust: Optional[float]
    min_thrust: Optional[float]
    max_tilt: Optional[float]
    max_acceleration_change: Optional[float]
    gravity: float

class Curve:
    def __init__(self, pieces: Sequence[ArrayLike]) -> None: ...
    @staticmethod
    def from_waypoints(waypoints: ArrayLike, kind: str = "minjerk") -> Curve: ...
    @staticmethod
    def load(path: str) -> Curve: ...
    @property
    def num_pieces(self) -> int: ...
    @property
    def pieces(self) -> list[Array]: ...
    def evaluate(self, sigma: ArrayLike, derivative: int = 0) -> Array: ...
    def arc_length(self) -> float: ...
    def to_json(self) -> str: ...

class TemporalProblem:
    def __init__(self, curve: Curve, limits: Limits = ..., *, K: int = 50, constraint_mode: str = "certified",
                 rho: float = 0.0, start_velocity: Optional[ArrayLike] = None, end_velocity: Optional[ArrayLike] = None,
                 start_acceleration: Optional[ArrayLike] = None, end_acceleration: Optional[ArrayLike] = None,
                 relax_boundary: bool = False) -> None: ...
    curve: Curve
    limits: Limits
    K: int
    constraint_mode: ConstraintMode
    rho: float
    relax_boundary: bool
    start_velocity: Array
    end_velocity: Array
    start_acceleration: Array
    end_acceleration: Array
    def validate(self) -> None: ...

def load_problem(path: str) -> TemporalProblem: ...
def parse_problem(json_text: str) -> TemporalProblem: ...

class TemporalProfile:
    @property
    def total_time(self) -> float: ...
    @property
    def num_pieces(self) -> int: ...
    @property
    def K(self) -> int: ...
    @property
    def jerk_limited(self) -> bool: ...
    @property
    def b(self) -> Array: ...

class TemporalResult:
    status: TemporalStatus
    message: str
    solver: str
    total_time: float
    objective: float
    piece_durations: Array
    iterations: int
    solve_time_seconds: float
    build_time_seconds: float
    profile: TemporalProfile
    max_velocity_ratio: float
    max_acceleration_ratio: float
    max_jerk_ratio: float
    max_speed_ratio: Optional[float]
    max_thrust_ratio: Optional[float]
    max_tilt_ratio: Optional[float]
    jerk_limited: bool
    scp_iterations: int
    reduced_accuracy: bool
    method: str
    infeasibility: Optional[dict[str, str]]
    boundary_relaxation: Optional[dict[str, Union[float, str]]]
    def is_success(self) -> bool: ...
    def to_json(self) -> str: ...

def solve(problem: TemporalProblem, solver: str = "socp", max_memory_mb: float = 0.0) -> TemporalResult: ...
def time_solves(problem: TemporalProblem, solver: str = "socp", repeats: int = 20) -> list[float]: ...

class Solver:
    def __init__(self, solver: str = "socp", max_memory_mb: float = 0.0) -> None: ...
    def solve(self, problem: TemporalProblem) -> TemporalResult: ...

class Trajectory:
    def __init__(self, curve: Curve, result: TemporalResult) -> None: ...
    @property
    def duration(self) -> float: ...
    def sample(self, ts: ArrayLike) -> Tuple[Array, Array, Array, Array]: ...
    def sample_rate(self, rate_hz: float) -> Tuple[Array, Tuple[Array, Array, Array, Array]]: ...
    @staticmethod
    def load(path: str) -> Trajectory: ...
    def save(self, path: str) -> None: ...
    def to_json(self) -> str: ...
    @staticmethod
    def from_json(text: str) -> Trajectory: ...
    def yaw(self, ts: ArrayLike, yaw: str = "velocity", max_yaw_rate: float = 1.0) -> Tuple[Array, Array]: ...
    def to_html(self, path: str, limits: Optional[Limits] = None, map: Optional[OccupancyMap] = None,
                title: str = "timeopt trajectory") -> None: ...

class OccupancyMap:
    @staticmethod
    def load(path: str, unknown: str = "free") -> OccupancyMap: ...
    @property
    def resolution(self) -> float: ...
    @property
    def bounds(self) -> Tuple[Array, Array]: ...
    def is_occupied(self, points: ArrayLike) -> npt.NDArray[np.bool_]: ...

class Esdf:
    @staticmethod
    def from_map(map: OccupancyMap, box_min: Optional[ArrayLike] = None, box_max: Optional[ArrayLike] = None,
                 max_memory_mb: float = 0.0) -> Esdf: ...
    @property
    def resolution(self) -> float: ...
    @property
    def memory_bytes(self) -> int: ...
    @property
    def domain(self) -> Tuple[Array, Array]: ...
    def distance(self, points: ArrayLike) -> Array: ...
    def distance_and_gradient(self, points: ArrayLike) -> Tuple[Array, Array]: ...

class PlanResult:
    status: PlanStatus
    message: str
    curve: Curve
    temporal: TemporalResult
    waypoints: Array
    path_length: float
    min_clearance: float
    min_interior_speed: float  # m/s, more than 1 s from either end (NaN: a flight of at most 2 s)
    min_curvature_radius: float  # m, over the same part
    start_scale: float
    total_time: float
    def is_success(self) -> bool: ...
    def trajectory(self) -> Trajectory: ...
    def summary(self) -> dict[str, Any]: ...
    def to_json(self) -> str: ...
    def to_html(self, path: str, map: Optional[OccupancyMap] = None, limits: Optional[Limits] = None) -> None: ...

def export(trajectory: Trajectory, format: str, path: str, rate_hz: float = 100.0, yaw: str = "velocity",
           max_yaw_rate: float = 1.0, map: Optional[OccupancyMap] = None, voxel_radius: float = 1.0,
           max_position_error: float = 1e-3, max_velocity_error: float = 1e-2,
           max_acceleration_error: float = 2e-2) -> None: ...
def plan(map: Union[Esdf, OccupancyMap, str], start: ArrayLike, goal: ArrayLike, **options: Any) -> PlanResult: ...

# Many problems at once (python/timeopt_batch.py): in order, equal to a loop of solve / plan; a
# failing item comes back as its result with a status. client: a dask.distributed.Client.
def solve_many(problems: Sequence[TemporalProblem], *, solver: str = "socp", threads: Optional[int] = None,
               client: Any = None, progress: Any = False, max_memory_mb: float = 0.0) -> list[TemporalResult]: ...
def plan_many(queries: Sequence[Any], *, threads: Optional[int] = None, client: Any = None, progress: Any = False,
              **options: Any) -> list[PlanResult]: ...

class FlightReport:
    feasible: bool
    tolerance: float
    message: str
    max_velocity_ratio: float
    max_acceleration_ratio: float
    max_jerk_ratio: float
    max_position_error: float
    final_position_error: float
    steps: int
    def to_json(self) -> str: ...

def simulate(trajectory: Trajectory, limits: Limits, *, bandwidth: float = 10.0, time_step: float = 1e-3,
             vehicle_max_jerk: Optional[ArrayLike] = None, tolerance: Optional[float] = None) -> FlightReport: ...

class conic:
    """The conic solver (a submodule at run time)."""

    class Status:
        optimal: conic.Status
        primal_infeasible: conic.Status
        dual_infeasible: conic.Status
        iteration_limit: conic.Status
        numerical_error: conic.Status
        name: str
        value: int

    class Result:
        status: conic.Status
        message: str
        x: Array
        y: Array
        z: Array
        s: Array
        primal_objective: float
        dual_objective: float
        iterations: int
        solve_time_seconds: float
        reduced_accuracy: bool

    @staticmethod
    def solve(c: ArrayLike, G: Any, h: ArrayLike, A: Any = None, b: Optional[ArrayLike] = None,
              cones: dict[str, Any] = ..., **options: Any) -> conic.Result: ...
    @staticmethod
    def read_cbf(path: str) -> dict[str, Any]: ...
    @staticmethod
    def write_cbf(path: str, c: ArrayLike, G: Any, h: ArrayLike, A: Any = None, b: Optional[ArrayLike] = None,
                  cones: dict[str, Any] = ...) -> None: ...
