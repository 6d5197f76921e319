"""Fixtures of the Python module's tests: a small bundle made by the real tools (lazyboe-build,
lazyboe-perturb) in pytest's temporary directory (ctest puts it in the build tree, afresh),
and the paths of the tools and the sources."""

import os
import pathlib
import subprocess

import pytest

TOOLS = pathlib.Path(os.environ.get("LAZYBOE_TOOLS_DIR", "build/bin"))
SOURCE = pathlib.Path(os.environ.get("LAZYBOE_SOURCE_DIR", pathlib.Path(__file__).parents[2]))

# The install example's bundle: 600 edges around a start in the empty environment.
REGION = "-0.3:0.3,0.0:0.5,-0.3:0.3,-2.3:-1.7,-0.3:0.3,1.6:2.2,0.5:1.1"
REGION_ROWS = ([-0.3, 0.0, -0.3, -2.3, -0.3, 1.6, 0.5], [0.3, 0.5, 0.3, -1.7, 0.3, 2.2, 1.1])
EDGES = 600
THETA = 0.45
PERTURBATIONS = 2
START = [0, 0.25, 0, -2, 0, 1.9, 0.8]
GOAL = [0.2, 0.1, 0.15, -1.85, -0.15, 2.0, 0.9]


def tool(name, *args, **kwargs):
    return subprocess.run([str(TOOLS / name), *map(str, args)], check=True, capture_output=True,
                          text=True, **kwargs)


def without_timings(d):
    """A result line without its wall times (and line number), which no two runs share."""
    d.pop("time_to_first_solution")
    for timing in ("planning_seconds", "time_to_executable", "line"):
        d.pop(timing, None)
    for timing in ("seconds", "raw_seconds"):
        d.get("post_processing", {}).pop(timing, None)
    return d


def empty_env():
    return SOURCE / "data" / "environments" / "empty.json"


def build_with_tools(path, perturb=True):
    tool("lazyboe-build", "--out", path, "--edges", EDGES, f"--region={REGION}", "--theta", THETA,
         "--env", empty_env(), "--quiet", "--force")
    if perturb:
        tool("lazyboe-perturb", "--bundle", path, "--perturbations", PERTURBATIONS, "--quiet")
    return path


@pytest.fixture(scope="session")
def bundle_path(tmp_path_factory):
    """A perturbed bundle made by the tools."""
    return build_with_tools(tmp_path_factory.mktemp("bundle") / "small.h5")


@pytest.fixture(scope="session")
def unperturbed_path(tmp_path_factory):
    """The same bundle without its perturbation analysis."""
    return build_with_tools(tmp_path_factory.mktemp("plain") / "plain.h5", perturb=False)


@pytest.fixture(scope="session")
def session(bundle_path):
    import lazyboe
    return lazyboe.PlanningSession(bundle_path)
