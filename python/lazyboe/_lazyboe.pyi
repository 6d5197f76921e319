"""Type stubs of the extension module lazyboe._lazyboe (the docstrings are in the module
itself: help(lazyboe.Robot) and so on)."""

from os import PathLike
from typing import Any, Callable, Iterable, Optional, Union

import numpy as np
import numpy.typing as npt

__version__: str
Path = Union[str, PathLike]
ArrayLike = npt.ArrayLike
Progress = Callable[[int, int], Any]

def data_dir() -> str: ...
def default_robot_path() -> str: ...

class Environment:
    name: str
    path: str
    description: str
    obstacles: list[str]
    def __init__(self, path: Optional[Path] = None) -> None: ...

class CollisionChecker:
    def in_collision(self, q: ArrayLike) -> Union[bool, npt.NDArray[np.bool_]]: ...
    def min_distance(self, q: ArrayLike) -> Union[float, npt.NDArray[np.float64]]: ...

class Robot:
    name: str
    config_path: str
    dof: int
    control_rate: float
    joints: list[dict[str, Any]]
    links: list[dict[str, Any]]
    joint_names: list[str]
    link_names: list[str]
    lower: npt.NDArray[np.float64]
    upper: npt.NDArray[np.float64]
    velocity_limits: npt.NDArray[np.float64]
    acceleration_limits: npt.NDArray[np.float64]
    jerk_limits: npt.NDArray[np.float64]
    effort_limits: npt.NDArray[np.float64]
    torque_rate_limits: npt.NDArray[np.float64]
    region_lower: npt.NDArray[np.float64]
    region_upper: npt.NDArray[np.float64]
    def __init__(self, config: Optional[Path] = None) -> None: ...
    def forward_kinematics(self, q: ArrayLike, link: Optional[str] = None) -> npt.NDArray[np.float64]: ...
    def inverse_dynamics(self, q: ArrayLike, dq: ArrayLike, ddq: ArrayLike) -> npt.NDArray[np.float64]: ...
    def forward_dynamics(self, q: ArrayLike, dq: ArrayLike, tau: ArrayLike) -> npt.NDArray[np.float64]: ...
    def gravity_torques(self, q: ArrayLike) -> npt.NDArray[np.float64]: ...
    def friction_torques(self, dq: ArrayLike) -> npt.NDArray[np.float64]: ...
    def mass_matrix(self, q: ArrayLike) -> npt.NDArray[np.float64]: ...
    def collision_checker(self, env: Union[Environment, Path, None] = None) -> CollisionChecker: ...
    def in_collision(self, q: ArrayLike, env: Union[Environment, Path, None] = None) -> Union[bool, npt.NDArray[np.bool_]]: ...

class Bundle:
    path: str
    header: dict[str, Any]
    dof: int
    size: int
    memory_mapped: bool
    warnings: list[str]
    has_perturbation: bool
    perturbation_theta: Optional[float]
    q0: npt.NDArray[np.float64]
    qf: npt.NDArray[np.float64]
    duration: npt.NDArray[np.float64]
    command_duration: npt.NDArray[np.float64]
    p_lazy_prop: Optional[npt.NDArray[np.float64]]
    p_collision: Optional[npt.NDArray[np.float64]]
    p_lazy_prop_transfer: Optional[npt.NDArray[np.float64]]
    transfer_max_error: Optional[npt.NDArray[np.float64]]
    def __init__(self, path: Path, memory_map: bool = True) -> None: ...
    def __len__(self) -> int: ...
    def command(self, edge: int) -> dict[str, Any]: ...
    def inspect(self) -> str: ...

class Trajectory:
    t: npt.NDArray[np.float64]
    q: npt.NDArray[np.float64]
    dq: npt.NDArray[np.float64]
    ddq: npt.NDArray[np.float64]
    cmd: npt.NDArray[np.float64]
    edges: npt.NDArray[np.int64]
    cost: float
    duration: float
    stops: int
    def __len__(self) -> int: ...

class PlanResult:
    id: str
    planner: str
    success: bool
    time_to_first_solution: Optional[float]
    planning_seconds: float
    time_to_executable: Optional[float]
    n_solutions: int
    best_cost: Optional[float]
    counters: dict[str, int]
    failure: Optional[str]
    found_by: Optional[str]
    duration: Optional[float]
    edges: Optional[npt.NDArray[np.int64]]
    trajectory: Optional[Trajectory]
    error: Optional[str]
    scene: dict[str, str]
    def to_dict(self) -> dict[str, Any]: ...

class Scene:
    name: str
    hash: str
    obstacles: list[str]
    marked_edges: int | None

class PlanningSession:
    robot: Robot
    bundle: Bundle
    load_seconds: float
    index_source: str
    workspace_index_source: str
    default_theta: float
    scene: dict[str, str]
    def __init__(self, bundle_path: Path, memory_map: bool = True, robot: Optional[Path] = None,
                 env: Optional[Path] = None) -> None: ...
    def plan(self, start: ArrayLike, goal: dict[str, Any], planner: str = "lazyboe",
             budget: Optional[float] = None, seed: Optional[int] = None, id: str = "",
             scene: Union[Scene, Path, dict[str, Any], None] = None, sample_interval: float = 0.01, sim_threads: int = 1, raw: bool = False,
             **params: Any) -> PlanResult: ...
    def load_scene(self, env: Union[Path, dict[str, Any]]) -> Scene: ...
    def plan_many(self, queries: Iterable[dict[str, Any]], jobs: int = 0,
                  sample_interval: float = 0.01, raw: bool = False) -> list[PlanResult]: ...

def planners() -> list[dict[str, Any]]: ...

def build_bundle(out: Path, *, robot: Optional[Path] = None, env: Optional[Path] = None,
                 edges: Optional[int] = None, seed: Optional[int] = None,
                 region: Union[str, tuple[ArrayLike, ArrayLike], None] = None,
                 theta: Optional[float] = None, min_duration: Optional[float] = None,
                 max_duration: Optional[float] = None, knot_interval: Optional[float] = None,
                 velocity_scale: Optional[float] = None, limit_scale: Optional[float] = None,
                 integrator: Optional[str] = None, substeps: Optional[int] = None,
                 sample_interval: Optional[float] = None, threads: int = 0,
                 checkpoint_seconds: float = 10.0, resume: bool = False, force: bool = False,
                 progress: Optional[Progress] = None, quiet: bool = True) -> Bundle: ...

def perturb_bundle(bundle: Path, *, theta: Optional[float] = None, perturbations: int = 16,
                   seed: int = 1, robot: Optional[Path] = None, env: Optional[Path] = None,
                   replace: bool = False, threads: int = 0, checkpoint_seconds: float = 10.0,
                   progress: Optional[Progress] = None, quiet: bool = True) -> Bundle: ...
