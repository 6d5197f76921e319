"""LazyBoE from Python: load a robot, open and inspect edge bundles, build and perturb them,
and plan kinodynamic motions, with NumPy arrays in and out, at C++ speed.

Everything here is the C++ library itself (the extension module ``lazyboe._lazyboe``); see
docs/python.md. Errors carry the library's one-line messages: ValueError for bad input,
OSError for files, RuntimeError otherwise.

    >>> import lazyboe
    >>> session = lazyboe.PlanningSession("build/demo/bundle.h5")
    >>> r = session.plan(start, {"q": goal, "tolerance": 0.1}, planner="lazyboe", seed=1)
    >>> r.success, r.best_cost, r.trajectory.q.shape
"""

from ._lazyboe import (  # noqa: F401
    Bundle,
    CollisionChecker,
    Environment,
    PlanningSession,
    PlanResult,
    Robot,
    Scene,
    Trajectory,
    __version__,
    build_bundle,
    data_dir,
    default_robot_path,
    perturb_bundle,
    planners,
)
from .task import EndEffectorLimits, Payload, Pose  # noqa: F401

__all__ = [
    "Bundle",
    "CollisionChecker",
    "EndEffectorLimits",
    "Environment",
    "Payload",
    "PlanningSession",
    "PlanResult",
    "Pose",
    "Robot",
    "Scene",
    "Trajectory",
    "__version__",
    "build_bundle",
    "data_dir",
    "default_robot_path",
    "perturb_bundle",
    "planners",
]
