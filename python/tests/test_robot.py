"""lazyboe.Robot: one-state and vectorized calls agree, match the tools, and bad input raises."""

import json

import numpy as np
import pytest

import lazyboe
from conftest import SOURCE, tool

READY = [0, -0.785, 0, -2.356, 0, 1.571, 0.785]


@pytest.fixture(scope="module")
def robot():
    return lazyboe.Robot()


@pytest.fixture(scope="module")
def states(robot):
    rng = np.random.default_rng(5)
    n = 200
    q = rng.uniform(robot.lower, robot.upper, (n, 7))
    dq = rng.uniform(-robot.velocity_limits, robot.velocity_limits, (n, 7))
    ddq = rng.uniform(-robot.acceleration_limits, robot.acceleration_limits, (n, 7))
    return q, dq, ddq


def test_model(robot):
    assert robot.name == "panda" and robot.dof == 7
    assert len(robot.joint_names) == 7 and robot.link_names[-1]
    assert (robot.lower < robot.upper).all()
    assert robot.control_rate == 1000
    joints = robot.joints
    assert [j["name"] for j in joints] == robot.joint_names
    assert [j["lower"] for j in joints] == robot.lower.tolist()
    assert [j["max_velocity"] for j in joints] == robot.velocity_limits.tolist()
    assert all(j["type"] == "revolute" and j["friction"]["model"] != "none" for j in joints)
    links = robot.links
    assert [l["name"] for l in links] == robot.link_names and links[0]["body"] == -1
    assert links[-1]["body"] == robot.dof - 1


def test_vectorized_equals_one_state(robot, states):
    q, dq, ddq = states
    tau = robot.inverse_dynamics(q, dq, ddq)
    fk, M = robot.forward_kinematics(q), robot.mass_matrix(q)
    acc = robot.forward_dynamics(q, dq, tau)
    g, f = robot.gravity_torques(q), robot.friction_torques(dq)
    assert tau.shape == (len(q), 7) and fk.shape == (len(q), 4, 4) and M.shape == (len(q), 7, 7)
    for k in range(len(q)):
        np.testing.assert_array_equal(tau[k], robot.inverse_dynamics(q[k], dq[k], ddq[k]))
        np.testing.assert_array_equal(fk[k], robot.forward_kinematics(q[k]))
        np.testing.assert_array_equal(M[k], robot.mass_matrix(q[k]))
        np.testing.assert_array_equal(acc[k], robot.forward_dynamics(q[k], dq[k], tau[k]))
        np.testing.assert_array_equal(g[k], robot.gravity_torques(q[k]))
        np.testing.assert_array_equal(f[k], robot.friction_torques(dq[k]))
    # Forward dynamics inverts inverse dynamics.
    np.testing.assert_allclose(acc, ddq, atol=1e-7)


def test_forward_kinematics_matches_the_tool(robot):
    for link in (None, robot.link_names[3]):
        args = ["fk", "--q", ",".join(map(str, READY))] + (["--link", link] if link else [])
        out = json.loads(tool("lazyboe-robot", *args).stdout)
        pose = robot.forward_kinematics(READY, link=link)
        np.testing.assert_allclose(pose[:3, 3], out["position"], atol=1e-9)
        assert pose[3].tolist() == [0, 0, 0, 1]


def test_inverse_dynamics_matches_the_tool(robot, tmp_path):
    states = SOURCE / "data" / "examples" / "states.csv"
    out = tmp_path / "tau.csv"
    tool("lazyboe-robot", "torques", "--in", states, "--out", out)
    data = np.loadtxt(states, delimiter=",", skiprows=1)
    expected = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)
    tau = robot.inverse_dynamics(data[:, 0:7], data[:, 7:14], data[:, 14:21])
    np.testing.assert_allclose(tau, expected, rtol=1e-9, atol=1e-9)  # printed to 10 digits


def test_collision_matches_the_tool(robot, tmp_path):
    configs = SOURCE / "data" / "examples" / "configs.csv"
    env = SOURCE / "data" / "environments" / "table.json"
    out = tmp_path / "check.csv"
    tool("lazyboe-robot", "check", "--env", env, "--in", configs, "--out", out)
    expected = np.loadtxt(out, delimiter=",", skiprows=1, ndmin=2)  # printed to 10 digits
    q = np.loadtxt(configs, delimiter=",", skiprows=1, ndmin=2)
    checker = robot.collision_checker(lazyboe.Environment(env))
    hits, distance = checker.in_collision(q), checker.min_distance(q)
    assert hits.dtype == bool and hits.shape == (len(q),)
    assert hits.any() and not hits.all()  # the example has both
    np.testing.assert_array_equal(hits, (expected[:, 1] + expected[:, 2]) > 0)
    np.testing.assert_allclose(distance, expected[:, 3], rtol=1e-9, atol=1e-10)
    for k in range(len(q)):
        assert checker.in_collision(q[k]) == hits[k]
        assert robot.in_collision(q[k], env) == hits[k]
        assert checker.min_distance(q[k]) == distance[k]


@pytest.mark.parametrize("call, message", [
    (lambda r: r.forward_kinematics([0.0] * 6), "q: expected 7 values or an (N, 7) array, got shape (6,)"),
    (lambda r: r.forward_kinematics(np.zeros((3, 6))), "q: expected 7 values or an (N, 7) array, got shape (3, 6)"),
    (lambda r: r.forward_kinematics(np.zeros((2, 3, 7))), "got shape (2, 3, 7)"),
    (lambda r: r.forward_kinematics("abc"), "q: expected 7 values"),
    (lambda r: r.forward_kinematics([[1, 2], [3]]), "q: expected 7 values"),
    (lambda r: r.forward_kinematics([np.nan] * 7), "q: not a finite number"),
    (lambda r: r.forward_kinematics(READY, link="nope"), "link: unknown link 'nope'"),
    (lambda r: r.forward_kinematics(READY, link=3), "link: expected a link name"),
    (lambda r: r.inverse_dynamics(np.zeros((3, 7)), np.zeros((2, 7)), np.zeros((3, 7))), "dq: expected the shape"),
    (lambda r: r.inverse_dynamics(READY, np.zeros((2, 7)), READY), "dq: expected the shape"),
    (lambda r: r.mass_matrix(None), "q: expected 7 values"),
])
def test_bad_input_raises_value_error(robot, call, message):
    with pytest.raises(ValueError) as e:
        call(robot)
    assert message in str(e.value)


def test_bad_files_raise_os_error(tmp_path):
    with pytest.raises(OSError, match="missing.json"):
        lazyboe.Robot(tmp_path / "missing.json")
    bad = tmp_path / "bad.json"
    bad.write_text("{")
    with pytest.raises(OSError, match="bad.json"):
        lazyboe.Robot(bad)
    with pytest.raises(OSError, match="nothere.json"):
        lazyboe.Environment(tmp_path / "nothere.json")
