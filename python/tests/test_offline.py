"""build_bundle / perturb_bundle: the tools' bundles, a progress callback, and a clean stop
(Ctrl-C or an exception in the callback) that leaves a resumable file."""

import json
import pathlib
import signal
import subprocess
import sys

import numpy as np
import pytest

import lazyboe
from conftest import EDGES, PERTURBATIONS, REGION_ROWS, THETA, empty_env

DATASETS = ["q0", "qf", "duration", "command_duration"]
ANALYSIS = ["p_lazy_prop", "p_collision", "p_lazy_prop_transfer", "transfer_max_error"]


def build(out, **kwargs):
    return lazyboe.build_bundle(out, edges=EDGES, region=REGION_ROWS, theta=THETA,
                                env=empty_env(), **kwargs)


def assert_same(a, b, names):
    for name in names:
        np.testing.assert_array_equal(getattr(a, name), getattr(b, name), err_msg=name)


def test_build_and_perturb_equal_the_tools(tmp_path, bundle_path):
    calls = []
    b = build(tmp_path / "b.h5", threads=1, progress=lambda done, total: calls.append((done, total)))
    assert len(b) == EDGES and b.header["complete"] and not b.has_perturbation
    tools = lazyboe.Bundle(bundle_path)
    assert_same(b, tools, DATASETS)
    assert calls[-1] == (EDGES, EDGES) and all(t == EDGES for _, t in calls)
    index = tmp_path / "b.h5.kd-index"  # written as lazyboe-build writes it, and used
    assert index.read_bytes() == pathlib.Path(str(bundle_path) + ".kd-index").read_bytes()
    assert lazyboe.PlanningSession(tmp_path / "b.h5").index_source == f"mapped from {index}"
    assert [d for d, _ in calls] == sorted(d for d, _ in calls)

    calls.clear()
    p = lazyboe.perturb_bundle(tmp_path / "b.h5", perturbations=PERTURBATIONS,
                               progress=lambda done, total: calls.append((done, total)))
    assert p.has_perturbation and p.perturbation_theta == THETA
    assert_same(p, tools, DATASETS + ANALYSIS)
    assert calls[-1] == (EDGES, EDGES)


class Stop(Exception):
    pass


def test_stopped_build_resumes_to_the_same_bundle(tmp_path, bundle_path):
    out = tmp_path / "stopped.h5"

    def stop_at_first_round(done, total):
        if done > 0:
            raise Stop()

    with pytest.raises(Stop):
        build(out, threads=1, progress=stop_at_first_round)
    with pytest.raises(OSError, match="incomplete|not complete|resume"):
        lazyboe.Bundle(out)  # a checkpoint, not a finished bundle
    b = lazyboe.build_bundle(out, resume=True)  # every setting from the file
    assert_same(b, lazyboe.Bundle(bundle_path), DATASETS)


def test_ctrl_c_stops_cleanly(tmp_path, bundle_path):
    out = tmp_path / "interrupted.h5"
    build(out)

    def interrupt(done, total):
        if done > 0:
            signal.raise_signal(signal.SIGINT)

    with pytest.raises(KeyboardInterrupt):
        lazyboe.perturb_bundle(out, perturbations=PERTURBATIONS, threads=1, progress=interrupt)
    assert not lazyboe.Bundle(out).has_perturbation  # the analysis is saved unfinished
    p = lazyboe.perturb_bundle(out, perturbations=PERTURBATIONS)  # continues it
    assert_same(p, lazyboe.Bundle(bundle_path), DATASETS + ANALYSIS)


@pytest.mark.parametrize("kwargs, error, message", [
    (dict(edges=0), ValueError, "edges: must be > 0"),
    (dict(theta=-1), ValueError, "theta: must be > 0"),
    (dict(velocity_scale=2), ValueError, "velocity_scale: must be in (0, 1]"),
    (dict(max_duration=0.1), ValueError, "max_duration: must be >= min_duration"),
    (dict(integrator="leapfrog"), ValueError, "integrator"),
    (dict(region=([0] * 7,)), ValueError, "region"),
    (dict(region=5), ValueError, "region: expected 'default', 'limits' or (lower, upper)"),
    (dict(region="everywhere"), ValueError, "region: expected"),
    (dict(edges="many"), ValueError, "edges: expected a whole number >= 0"),
    (dict(edges=-5), ValueError, "edges: expected a whole number >= 0"),
    (dict(theta="wide"), ValueError, "theta: expected a number"),
    (dict(region=([0] * 6, [1] * 6)), ValueError, "region lower: expected 7 values"),
    (dict(robot="/nonexistent/robot.json"), OSError, "robot.json"),
    (dict(resume=True), OSError, "cannot resume: no such file"),
])
def test_bad_build_settings(tmp_path, kwargs, error, message):
    with pytest.raises(error) as e:
        lazyboe.build_bundle(tmp_path / "x.h5", **kwargs)
    assert message in str(e.value)
    assert not (tmp_path / "x.h5").exists()


def test_existing_file_is_not_overwritten(tmp_path):
    out = tmp_path / "exists.h5"
    out.write_text("keep")
    with pytest.raises(OSError, match="already exists"):
        lazyboe.build_bundle(out, edges=10)
    assert out.read_text() == "keep"


def test_bad_perturb_settings(bundle_path, tmp_path):
    copy = tmp_path / "copy.h5"
    copy.write_bytes(bundle_path.read_bytes())
    with pytest.raises(ValueError, match="perturbations: must be > 0"):
        lazyboe.perturb_bundle(copy, perturbations=0)
    with pytest.raises(ValueError, match="theta"):  # another analysis without replace=True
        lazyboe.perturb_bundle(copy, theta=0.3, perturbations=PERTURBATIONS)
    assert copy.read_bytes() == bundle_path.read_bytes()
    with pytest.raises(OSError, match="missing.h5"):
        lazyboe.perturb_bundle(tmp_path / "missing.h5")


BUILD_SCRIPT = """
import sys, lazyboe
def progress(done, total):
    print(done, flush=True)
try:
    lazyboe.build_bundle(sys.argv[1], edges=int(sys.argv[2]), threads=1, progress=progress)
except KeyboardInterrupt:
    print("interrupted", flush=True)
    sys.exit(130)
"""


def test_sigint_from_outside_stops_a_build(tmp_path, bundle_path):
    """A real Ctrl-C (SIGINT to the process while the library builds, not from a callback)."""
    out = tmp_path / "sigint.h5"
    script = tmp_path / "build.py"
    script.write_text(BUILD_SCRIPT)
    child = subprocess.Popen([sys.executable, str(script), str(out), "100000"],
                             stdout=subprocess.PIPE, text=True)
    assert child.stdout.readline().strip() == "0"  # the build has started
    child.send_signal(signal.SIGINT)
    rest = child.stdout.read()
    assert child.wait(timeout=60) == 130 and rest.endswith("interrupted\n")
    with pytest.raises(OSError):
        lazyboe.Bundle(out)  # a checkpoint of an unfinished build
    done = int(rest.split()[-2]) if len(rest.split()) > 1 else 0
    b = lazyboe.build_bundle(out, resume=True, edges=max(done, 1) + 64)
    assert len(b) == max(done, 1) + 64


def test_a_hopeless_build_stops_early_with_the_reason(tmp_path):
    # Torque-rate limits of 1 N m/s reject every motion: the build stops after 2000 attempts
    # with the reason and what to change, and the partial bundle stays readable.
    source = pathlib.Path(lazyboe.data_dir()) / "robots"
    config = json.loads((source / "panda.json").read_text())
    for joint in config["joints"]:
        joint["max_torque_rate"] = 1
    config["urdf"] = str(source / "panda.urdf")
    robot = tmp_path / "slow.json"
    robot.write_text(json.dumps(config))
    out = tmp_path / "b.h5"
    with pytest.raises(RuntimeError, match="stopped after the first 2000 attempts") as e:
        lazyboe.build_bundle(out, edges=100, robot=robot)
    assert "torque_rate_limit 100.0%" in str(e.value) and "resume=True" in str(e.value)
    with pytest.raises(OSError, match=r"incomplete bundle \(0 of 100 edges\)"):
        lazyboe.Bundle(out)  # a valid file that says what it is
