"""Scenes at query time: one session plans in any scene of its robot, as lazyboe-query does."""

import json

import pytest

import lazyboe
from conftest import GOAL, SOURCE, START, empty_env, tool, without_timings

TABLE = SOURCE / "data" / "environments" / "table.json"


def plan(session, **kwargs):
    return session.plan(START, {"q": GOAL, "tolerance": 0.1}, planner="boe", seed=3, budget=20,
                        stop_at_first=True, **kwargs)


def test_a_scene_by_path_and_inline_is_one_scene(session):
    by_path = plan(session, scene=TABLE)
    inline = plan(session, scene=json.loads(TABLE.read_text()))
    assert by_path.success
    assert by_path.scene["name"] == "table"
    assert by_path.scene == inline.scene
    assert without_timings(by_path.to_dict()) == without_timings(inline.to_dict())
    assert session.scene["name"] == "empty"  # the bundle's own, unchanged
    assert plan(session).scene == session.scene


def test_switching_scenes_answers_as_separate_sessions(session, bundle_path):
    mixed = [plan(session, scene=s) for s in (empty_env(), TABLE, empty_env())]
    for scene, result in zip((empty_env(), TABLE, empty_env()), mixed):
        alone = lazyboe.PlanningSession(bundle_path, env=scene)
        assert without_timings(plan(alone).to_dict()) == without_timings(result.to_dict())
    assert mixed[0].scene != mixed[1].scene
    assert without_timings(mixed[0].to_dict()) == without_timings(mixed[2].to_dict())


def test_plan_many_takes_a_scene_per_query(session, bundle_path, tmp_path):
    queries = [{"id": f"q{k}", "start": START, "goal": {"q": GOAL, "tolerance": 0.1},
                "planner": "boe", "seed": 3, "budget": 20, "stop_at_first": True,
                "scene": str(s)} for k, s in enumerate((TABLE, empty_env()))]
    f = tmp_path / "q.jsonl"
    f.write_text("".join(json.dumps(q) + "\n" for q in queries))
    lines = [json.loads(l) for l in tool("lazyboe-query", "--bundle", bundle_path, "--queries", f,
                                         "--trajectories", "inline", "--quiet").stdout.splitlines()]
    results = session.plan_many(queries, jobs=2)
    for r, line in zip(results, lines):
        assert without_timings(r.to_dict()) == without_timings(line)
    assert [r.scene["name"] for r in results] == ["table", "empty"]


@pytest.mark.parametrize("scene, message", [
    ("no-such-scene.json", "scene: no-such-scene.json"),
    ({"schema_version": 1, "name": "x", "objects": [{"name": "b", "type": "box"}]},
     "scene.objects[0].size: missing required field"),
    ({"schema_version": 1, "name": "x", "objects": [
        {"name": "f", "type": "sphere", "radius": 0.1, "position": [2, 0, 0],
         "allowed_links": ["base_link"]}]}, "allowed link 'base_link' is not a link"),
])
def test_a_bad_scene_raises_value_error_naming_it(session, scene, message):
    with pytest.raises(ValueError) as e:
        plan(session, scene=scene)
    assert message in str(e.value)
    assert "\n" not in str(e.value)


def test_a_loaded_scene_plans_as_its_file_does(session):
    scene = session.load_scene(TABLE)
    assert scene.name == "table" and "table_top" in scene.obstacles
    loaded = plan(session, scene=scene)
    by_path = plan(session, scene=TABLE)
    assert loaded.scene == {"name": "table", "hash": scene.hash}
    assert without_timings(loaded.to_dict()) == without_timings(by_path.to_dict())
    # The start is checked in the loaded scene: a start inside one of its obstacles is refused.
    inside = {"schema_version": 1, "name": "ball", "objects": [
        {"name": "ball", "type": "sphere", "radius": 0.3, "position": [0.4, 0.0, 0.5]}]}
    with pytest.raises(ValueError, match="start: in collision"):
        plan(session, scene=session.load_scene(inside))


def test_load_scene_errors(session, tmp_path):
    with pytest.raises(OSError, match="nothing.json"):
        session.load_scene(tmp_path / "nothing.json")
    with pytest.raises(ValueError, match="env.objects"):
        session.load_scene({"schema_version": 1, "name": "x"})


def test_the_workspace_index_steers_lazysp_in_another_scene(session, bundle_path):
    # lazyboe-build wrote it beside the bundle; the session maps it, and a scene other than the
    # bundle's (empty) gets its marks: the same answer as a session opened in that scene.
    assert session.workspace_index_source == f"mapped from {bundle_path}.ws-index"
    kwargs = dict(planner="lazysp", seed=3, budget=20, stop_at_first=True)
    mixed = session.plan(START, {"q": GOAL, "tolerance": 0.1}, scene=TABLE, **kwargs)
    alone = lazyboe.PlanningSession(bundle_path, env=TABLE).plan(
        START, {"q": GOAL, "tolerance": 0.1}, **kwargs)
    assert mixed.success
    assert without_timings(mixed.to_dict()) == without_timings(alone.to_dict())
    # The table's obstacles are new to a bundle built on the floor alone: some edges are marked.
    table = session.load_scene(TABLE)
    assert 0 < table.marked_edges < session.bundle.size
    assert session.load_scene(empty_env()).marked_edges is None  # the bundle's own scene
