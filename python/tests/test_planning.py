"""PlanningSession.plan / plan_many: the same answers as lazyboe-query, errors as exceptions."""

import json
import os
import signal
import subprocess
import time
import threading

import numpy as np
import pytest

import lazyboe
from conftest import GOAL, START, TOOLS, tool, without_timings

# Queries every planner family answers deterministically (stop_at_first, generous budget).
QUERIES = [
    {"id": "lazyboe-1", "planner": "lazyboe", "seed": 1},
    {"id": "lazyboe-7", "planner": "lazyboe", "seed": 7},
    {"id": "boe-3", "planner": "boe", "seed": 3},
    {"id": "rrt-2", "planner": "rrt", "seed": 2},
    {"id": "lazysp-1", "planner": "lazysp", "seed": 1},
    # The flange to where GOAL puts it (lazyboe-robot fk; rounded as a user would write it).
    {"id": "lazyboe-position", "planner": "lazyboe", "seed": 1,
     "goal": {"position": [0.5622, 0.1929, 0.4724], "tolerance": 0.03}},
    {"id": "rrt-position", "planner": "rrt", "seed": 4,
     "goal": {"position": [0.5622, 0.1929, 0.4724], "tolerance": 0.03}},
]


def query(q):
    return {"start": START, "goal": {"q": GOAL, "tolerance": 0.1}, "budget": 20,
            "stop_at_first": True, **q}


def run_tool(bundle_path, tmp_path_factory, *options):
    queries = tmp_path_factory.mktemp("queries") / "q.jsonl"
    queries.write_text("".join(json.dumps(query(q)) + "\n" for q in QUERIES))
    out = tool("lazyboe-query", "--bundle", bundle_path, "--queries", queries,
               "--trajectories", "inline", "--quiet", *options).stdout
    return {r["id"]: r for r in map(json.loads, out.splitlines())}


@pytest.fixture(scope="module")
def tool_results(bundle_path, tmp_path_factory):
    """lazyboe-query's default: executable (post-processed) trajectories."""
    return run_tool(bundle_path, tmp_path_factory)


@pytest.fixture(scope="module")
def tool_raw_results(bundle_path, tmp_path_factory):
    return run_tool(bundle_path, tmp_path_factory, "--raw")


def same_as_tool(result, line):
    """Every field of the result line but the timings and the line number."""
    assert without_timings(result.to_dict()) == without_timings(line)
    assert result.success == line["success"]
    if result.success:
        assert result.best_cost == line["best_cost"]
        assert result.edges.tolist() == line["edges"]
        assert result.trajectory.t.tolist() == line["trajectory"]["t"]
        assert result.trajectory.q.tolist() == line["trajectory"]["q"]
        assert result.trajectory.dq.tolist() == line["trajectory"]["dq"]
        if "post_processing" in line:
            assert result.trajectory.ddq.tolist() == line["trajectory"]["ddq"]
            assert result.trajectory.cmd.tolist() == line["trajectory"]["cmd"]
            assert result.trajectory.stops == line["stops"]
        else:
            assert result.trajectory.ddq.shape == (0, 7)


def test_plan_equals_lazyboe_query(session, tool_results):
    for q in QUERIES:
        r = session.plan(**query(q))
        assert r.success, r.failure
        same_as_tool(r, dict(tool_results[q["id"]]))


def test_plan_many_equals_lazyboe_query(session, tool_results):
    results = session.plan_many([query(q) for q in QUERIES], jobs=2)
    assert [r.id for r in results] == [q["id"] for q in QUERIES]
    for r in results:
        same_as_tool(r, dict(tool_results[r.id]))


def test_raw_equals_lazyboe_query_raw(session, tool_raw_results):
    for q in QUERIES:
        r = session.plan(**query(q), raw=True)
        assert r.success, r.failure
        same_as_tool(r, dict(tool_raw_results[q["id"]]))
    for r in session.plan_many([query(q) for q in QUERIES], jobs=2, raw=True):
        same_as_tool(r, dict(tool_raw_results[r.id]))


def test_executable_trajectory_is_shorter_to_run_than_the_raw_chain(session):
    q = query(QUERIES[0])
    executable, raw = session.plan(**q), session.plan(**q, raw=True)
    assert executable.edges.tolist() == raw.edges.tolist()  # the same planner answer
    assert executable.trajectory.stops < raw.trajectory.stops or raw.trajectory.stops == 0
    assert executable.trajectory.duration <= raw.trajectory.duration
    assert executable.to_dict()["raw_duration"] == pytest.approx(raw.trajectory.duration)


def test_result_attributes(session):
    r = session.plan(np.array(START), {"q": np.array(GOAL)}, planner="lazyboe", seed=1,
                     stop_at_first=True, budget=20)
    assert r.success and r.failure is None and r.n_solutions >= 1
    assert r.time_to_first_solution > 0
    assert set(r.counters) == {"nodes", "simulations", "lazy_edges", "collision_checks"}
    t = r.trajectory
    assert t.q.shape == (len(t.t), 7) and t.dq.shape == t.q.shape
    assert t.q[0].tolist() == START
    assert np.linalg.norm(t.q[-1] - GOAL) <= 0.1
    assert t.cost == r.best_cost and t.duration == r.duration == pytest.approx(t.t[-1])
    assert (np.diff(t.t) > 0).all()


def test_position_goal(session, tool_results):
    robot = session.robot
    target = robot.forward_kinematics(GOAL)[:3, 3]
    r = session.plan(START, {"position": target.tolist(), "tolerance": 0.03}, seed=1,
                     stop_at_first=True, budget=20)
    assert r.success, r.failure
    reached = robot.forward_kinematics(r.trajectory.q[-1])[:3, 3]
    assert np.linalg.norm(reached - target) <= 0.03


def rotation_angle(a, b):
    """Angle of the rotation between two rotation matrices, rad."""
    return float(np.arccos(np.clip((np.trace(a.T @ b) - 1) / 2, -1, 1)))


def test_pose_goal_and_the_task_at_query_time(session, tmp_path):
    """A pose goal, a payload and end-effector limits through plan(), as a query line has them;
    the end pose checked here, the trajectory by validate-trajectory with the same task."""
    robot = session.robot
    pose = robot.forward_kinematics(GOAL)
    w, x, y, z = [float(v) for v in quaternion(pose[:3, :3])]
    goal = {"pose": {"position": pose[:3, 3].tolist(), "orientation": [w, x, y, z]},
            "position_tolerance": 0.01, "orientation_tolerance": 0.05}
    payload = {"mass": 1.0, "com": [0, 0, 0.1]}
    limits = {"max_linear_acceleration": 3.0, "max_linear_speed": 1.0}
    r = session.plan(START, goal, planner="lazysp", seed=1, stop_at_first=True, budget=20,
                     payload=payload, end_effector_limits=limits, sample_interval=0.001)
    assert r.success, r.failure
    end = robot.forward_kinematics(r.trajectory.q[-1])
    assert np.linalg.norm(end[:3, 3] - pose[:3, 3]) <= 0.01
    assert rotation_angle(end[:3, :3], pose[:3, :3]) <= 0.05
    csv = tmp_path / "t.csv"
    t = r.trajectory
    header = ["t"] + [f"q{i + 1}" for i in range(7)] + [f"dq{i + 1}" for i in range(7)]
    rows = [[t.t[k], *t.q[k], *t.dq[k]] for k in range(len(t.t))]
    csv.write_text(",".join(header) + "\n" + "".join(",".join(repr(float(v)) for v in row) + "\n"
                                                      for row in rows))
    check = tool("lazyboe-robot", "validate-trajectory", "--in", csv, "--env", "table", "--payload",
                 json.dumps(payload), "--end-effector-limits", json.dumps(limits))
    assert check.stdout.startswith("valid"), check.stdout
    with pytest.raises(ValueError, match="payload.mass"):
        session.plan(START, goal, payload={"mass": -1})


def test_typed_task_objects_are_the_query_format(session):
    """lazyboe.Pose, Payload and EndEffectorLimits plan as their dicts do (same seed, same
    answer), and a free yaw about the tool axis is reached within tolerance otherwise."""
    robot = session.robot
    pose = robot.forward_kinematics(GOAL)
    goal = lazyboe.Pose.from_matrix(pose, free_axis=[0, 0, 1], orientation_tolerance=0.05)
    assert goal.to_query()["pose"]["orientation"] == pytest.approx(quaternion(pose[:3, :3]))
    payload = lazyboe.Payload(1.0, com=[0, 0, 0.1], box=[0.05, 0.05, 0.1])
    limits = lazyboe.EndEffectorLimits(max_linear_acceleration=3.0, max_tilt=1.0)
    options = dict(planner="lazysp", seed=2, stop_at_first=True, budget=20)
    typed = session.plan(START, goal, payload=payload, end_effector_limits=limits, **options)
    plain = session.plan(START, goal.to_query(), payload=payload.to_query(),
                         end_effector_limits=limits.to_query(), **options)
    assert typed.success, typed.failure
    assert np.array_equal(typed.trajectory.q, plain.trajectory.q)
    end = robot.forward_kinematics(typed.trajectory.q[-1])
    assert np.linalg.norm(end[:3, 3] - pose[:3, 3]) <= 0.01
    # Only rotations about the base's vertical are free: the link sees the vertical as the goal
    # pose does.
    up = np.array([0.0, 0.0, 1.0])
    assert np.arccos(np.clip((end[:3, :3].T @ up) @ (pose[:3, :3].T @ up), -1, 1)) <= 0.05
    with pytest.raises(ValueError, match="orientation: expected 4 numbers"):
        lazyboe.Pose([0.5, 0, 0.5], [1, 0, 0])
    water = lazyboe.Payload(None, box=[0.1, 0.1, 0.1], density=1000)
    assert water.to_query() == {"com": [0.0, 0.0, 0.0], "density": 1000.0, "box": [0.1] * 3}
    with pytest.raises(ValueError, match="payload.mass"):
        session.plan(START, goal, payload=lazyboe.Payload(-1.0))


def quaternion(m):
    """[w, x, y, z] of a rotation matrix (w >= 0), from the axis and angle (independent of
    lazyboe.Pose's conversion)."""
    angle = np.arccos(np.clip((np.trace(m) - 1) / 2, -1, 1))
    if angle < 1e-9:
        return [1.0, 0.0, 0.0, 0.0]
    if np.pi - angle < 1e-6:  # a half turn: the axis from the symmetric part
        axis = np.sqrt(np.clip((np.diag(m) + 1) / 2, 0, None))
        i = int(np.argmax(axis))
        axis = np.array([(m[i, j] + m[j, i]) / 2 for j in range(3)]) / axis[i]
        axis[i] = np.sqrt((m[i, i] + 1) / 2)
    else:
        axis = np.array([m[2, 1] - m[1, 2], m[0, 2] - m[2, 0], m[1, 0] - m[0, 1]])
    axis = axis / np.linalg.norm(axis)
    q = [np.cos(angle / 2), *(np.sin(angle / 2) * axis)]
    return [float(v) for v in (q if q[0] >= 0 else -np.array(q))]


def rotation_of(q):
    """The rotation matrix of a unit quaternion [w, x, y, z]."""
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def test_pose_from_a_matrix_keeps_every_rotation():
    """Pose.from_matrix gives the quaternion of the rotation, half turns included (a gripper
    pointing down is one: its diagonal terms decide the axis)."""
    rng = np.random.default_rng(4)
    down = np.diag([1.0, -1.0, -1.0])
    cases = [np.eye(3), down, np.diag([-1.0, 1.0, -1.0]), np.diag([-1.0, -1.0, 1.0])]
    for yaw in (-np.pi / 4, np.pi / 3, np.pi - 1e-9):
        c, s = np.cos(yaw), np.sin(yaw)
        cases.append(np.array([[c, -s, 0], [s, c, 0], [0, 0, 1]]) @ down)
    for _ in range(20):
        q = rng.normal(size=4)
        cases.append(rotation_of(q / np.linalg.norm(q)))
    for m in cases:
        t = np.eye(4)
        t[:3, :3] = m
        w = lazyboe.Pose.from_matrix(t).orientation
        assert np.abs(rotation_of(w) - m).max() < 1e-9, (m, w)
        assert w[0] >= 0


def test_no_solution_is_a_result(session):
    r = session.plan(START, {"q": GOAL, "tolerance": 0.1}, planner="rrt", budget=0.001, seed=1)
    assert not r.success
    assert r.trajectory is None and r.best_cost is None and r.edges is None
    assert r.failure


@pytest.mark.parametrize("kwargs, message", [
    (dict(start=START[:6]), "start: expected 7 joint values"),
    (dict(goal={"q": [9.0] * 7}), "goal.q: "),
    (dict(goal={"qq": GOAL}), "goal"),
    (dict(goal={"q": GOAL, "tolerance": -1}), "goal.tolerance"),
    (dict(planner="nope"), "planner: unknown planner 'nope'"),
    (dict(theta=-1.0), "theta: must be"),
    (dict(budget=0), "budget"),
    (dict(seed=-3), "seed: must be >= 0"),
    (dict(frobnicate=1), "frobnicate"),
    (dict(goal={"position": [0.5, 0, 0.5], "link": "nope"}), "goal.link: unknown link 'nope'"),
    (dict(goal=object()), "goal: cannot be given as object"),
    (dict(start="abc"), "start"),
])
def test_bad_query_raises_value_error(session, kwargs, message):
    args = {"start": START, "goal": {"q": GOAL}, **kwargs}
    with pytest.raises(ValueError) as e:
        session.plan(**args)
    assert message in str(e.value)
    assert "\n" not in str(e.value)


def test_bad_query_in_a_batch_names_it(session):
    with pytest.raises(ValueError, match=r"queries\[1\]: start: expected 7 joint values"):
        session.plan_many([query({}), query({"start": [0.0]})])


def test_message_is_the_librarys(session, bundle_path, tmp_path):
    """The same message as lazyboe-query gives for the same bad query (without its line)."""
    bad = query({"id": "bad", "goal": {"q": [9.0] * 7}})
    f = tmp_path / "bad.jsonl"
    f.write_text(json.dumps(bad) + "\n")
    # Every query of the batch had an error: exit status 1, the error result written all the same.
    r = subprocess.run([str(TOOLS / "lazyboe-query"), "--bundle", str(bundle_path), "--queries",
                        str(f), "--quiet"], capture_output=True, text=True)
    assert r.returncode == 1 and "every query had an error (1 of 1" in r.stderr
    line = json.loads(r.stdout)
    with pytest.raises(ValueError) as e:
        session.plan_many([bad])
    assert line["error"] == "line 1: " + str(e.value).removeprefix("queries[0]: ")


def test_missing_files_raise_os_error(tmp_path):
    with pytest.raises(OSError, match="nothing.h5"):
        lazyboe.PlanningSession(tmp_path / "nothing.h5")
    junk = tmp_path / "junk.h5"
    junk.write_bytes(b"not a bundle")
    with pytest.raises(OSError, match="junk.h5"):
        lazyboe.PlanningSession(junk)


def test_threads_plan_concurrently_with_the_same_results(session):
    qs = [query({"planner": "lazyboe", "seed": s}) for s in (11, 12)]
    sequential = [session.plan(**q).to_dict() for q in qs]
    concurrent = [None, None]

    def run(k):
        concurrent[k] = session.plan(**qs[k]).to_dict()

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    for a, b in zip(sequential, concurrent):
        assert without_timings(a) == without_timings(b)


def test_planners_lists_the_registry():
    ps = {p["name"]: p for p in lazyboe.planners()}
    assert {"lazyboe", "boe", "rrt", "sst", "lazysp"} <= set(ps)
    assert ps["lazyboe"]["needs"]["perturbation"]
    text = tool("lazyboe-query", "--list-planners").stdout
    for name, p in ps.items():
        assert name in text
        for param in p["parameters"]:
            assert param in text


def test_plan_releases_the_gil(session):
    """While one thread plans (for its whole 2 s budget), another runs Python code: 3,000,000 loop
    steps (about 50 ms of CPU) finish before the plan does. Holding the GIL, plan() would let
    the other thread run only before it enters the library (one switch interval, 5 ms)."""
    started, done = threading.Event(), threading.Event()
    q = query({"planner": "lazyboe", "seed": 5, "stop_at_first": False, "budget": 2.0,
               "direct": False})

    def run():
        started.set()
        session.plan(**q)
        done.set()

    worker = threading.Thread(target=run)
    worker.start()
    started.wait()
    steps = 0
    while steps < 3000000:
        steps += 1
    finished_first = not done.is_set()
    worker.join()
    assert finished_first


def test_a_free_straight_command_is_the_answer(session):
    """START -> GOAL is free in a straight line: the bundle planners answer with that one
    command (found_by direct, one simulation, no bundle edge), and search with direct=False."""
    for planner in ("lazyboe", "boe", "lazysp"):
        r = session.plan(**query({"planner": planner, "seed": 1}))
        assert r.success and r.found_by == "direct", (planner, r.failure, r.found_by)
        assert r.counters["simulations"] == 1
        assert list(r.edges) == [-1]
        assert r.time_to_executable >= r.time_to_first_solution
        assert r.to_dict()["post_processing"]["simulations"] == 0  # nothing simulated twice
        searching = {"planner": planner, "seed": 1, "direct": False}
        if planner == "lazysp":
            searching["candidate_shortcut"] = False  # its candidate's shortcut would be that command
        searched = session.plan(**query(searching))
        assert searched.success and searched.found_by != "direct", planner
        assert searched.counters["simulations"] > 1
    rrt = session.plan(**query({"planner": "rrt", "seed": 2}))
    assert rrt.found_by is None  # RRT has no direct connection of its own


def test_planner_needing_what_the_bundle_lacks_raises_runtime_error(unperturbed_path):
    plain = lazyboe.PlanningSession(unperturbed_path)
    with pytest.raises(RuntimeError, match="has no complete perturbation analysis"):
        plain.plan(START, {"q": GOAL}, planner="lazyboe")
    r = plain.plan(START, {"q": GOAL}, planner="boe", seed=1, stop_at_first=True, budget=20)
    assert r.success  # BoE needs no analysis


def test_ctrl_c_stops_a_batch(session):
    """SIGINT while plan_many runs 40 queries of 0.5 s each (10 s on two threads): the batch
    stops after the queries in flight and raises KeyboardInterrupt. (Without the stop, the
    interrupt would only come after the whole batch.)"""
    qs = [query({"planner": "lazyboe", "seed": k, "stop_at_first": False, "budget": 0.5,
                 "direct": False}) for k in range(40)]
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        session.plan_many(qs, jobs=2)
    timer.join()
    assert time.monotonic() - start < 5


def test_ctrl_c_stops_one_plan(session):
    """SIGINT during a single plan() of a 30 s budget stops it at the planner's next check."""
    timer = threading.Timer(0.3, os.kill, (os.getpid(), signal.SIGINT))
    start = time.monotonic()
    timer.start()
    with pytest.raises(KeyboardInterrupt):
        session.plan(START, {"q": GOAL, "tolerance": 0.1}, planner="lazyboe", budget=30, seed=1,
                     direct=False)
    timer.join()
    assert time.monotonic() - start < 2


def test_plan_many_gives_an_error_result_for_a_planner_that_fails(unperturbed_path):
    """lazyboe needs the perturbation analysis: its query gets an error, the others are planned."""
    s = lazyboe.PlanningSession(unperturbed_path)
    results = s.plan_many([query({"id": "a", "planner": "boe", "seed": 3}),
                           query({"id": "b", "planner": "lazyboe"}),
                           query({"id": "c", "planner": "rrt", "seed": 2})], jobs=2)
    assert [r.id for r in results] == ["a", "b", "c"]
    assert results[0].success and results[2].success
    assert not results[1].success
    assert "perturbation" in results[1].error
    assert results[1].failure.startswith("error: ")
    assert results[1].to_dict()["error"] == results[1].error
    assert results[0].error is None
