#!/usr/bin/env python3
"""lazyboe-view's pages in headless Chromium (issue 17): no console errors, the scene reports
the robot, the obstacles and the trajectories it loaded, a screenshot that is not blank where
the robot is, link poses equal to `lazyboe-robot fk` to 1e-6, and bad input (only failed
queries, results without trajectories) giving a page that says so.

Usage: test_viewer.py BIN_DIR OUT_DIR. Exits 77 (ctest: skipped) when Chromium is not installed.
The screenshot of the main page is OUT_DIR/viewer.png (the README's, docs/images/viewer.png)."""

import json
import math
import os
import random
import subprocess
import sys
import time

sys.path.insert(0, os.path.dirname(os.path.abspath(__file__)))
import chromium  # noqa: E402

SOURCE = os.path.dirname(os.path.dirname(os.path.dirname(os.path.abspath(__file__))))
READY = [0, -0.785, 0, -2.356, 0, 1.571, 0.785]
OTHER = [0.3, -0.5, 0.2, -2.0, 0.1, 1.8, 0.4]
THIRD = [-0.6, 0.3, -0.4, -1.4, 0.5, 2.2, -0.3]
BACKGROUND = (242, 243, 245)  # the scene's background colour (viewer.js)
failures = []


def check(condition, what):
    print(("ok      " if condition else "FAILED  ") + what)
    if not condition:
        failures.append(what)


def run(args):
    r = subprocess.run(args, capture_output=True, text=True)
    if r.returncode != 0:
        raise RuntimeError(f"{' '.join(args)}: exit {r.returncode}: {r.stderr.strip()}")
    return r.stdout


def trajectory_result(rid, line, a, b, samples=21):
    t = [i / (samples - 1) for i in range(samples)]
    q = [[x + s * (y - x) for x, y in zip(a, b)] for s in t]
    return {"id": rid, "line": line, "planner": "lazysp", "success": True,
            "time_to_first_solution": 0.01, "n_solutions": 1, "best_cost": 1.0, "duration": 1.0,
            "edges": [3, 5], "trajectory": {"t": t, "q": q, "dq": [[0] * 7] * samples}}


def failed_result(rid, line, failure):
    return {"id": rid, "line": line, "planner": "lazyboe", "success": False, "failure": failure,
            "time_to_first_solution": None, "n_solutions": 0, "best_cost": None}


def ur5_with_visuals(out_dir):
    """The UR5 with a <visual> beside every <collision> (the same geometry), the base's naming a
    mesh file that is not there: its config, and how many visuals can be read."""
    import re
    folder = os.path.join(out_dir, "ur5v")
    os.makedirs(folder, exist_ok=True)
    with open(os.path.join(SOURCE, "data", "robots", "ur5", "ur5.urdf")) as f:
        urdf = f.read()
    blocks = re.findall(r"<collision>.*?</collision>", urdf, re.S)
    for k, block in enumerate(blocks):
        visual = block.replace("<collision>", "<visual>").replace("</collision>", "</visual>")
        if k == 0:
            visual = re.sub(r'filename="[^"]+"', 'filename="package://ur_description/meshes/ur5/visual/gone.dae"', visual)
        urdf = urdf.replace(block, block + "\n    " + visual, 1)
    with open(os.path.join(folder, "ur5.urdf"), "w") as f:
        f.write(urdf)
    with open(os.path.join(SOURCE, "data", "robots", "ur5.json")) as f:
        config = json.load(f)
    config["urdf"] = "ur5.urdf"
    config["package_path"] = [os.path.join(SOURCE, "data", "robots", "ur5")]
    path = os.path.join(folder, "ur5v.json")
    with open(path, "w") as f:
        json.dump(config, f)
    return path, len(blocks) - 1


def write_lines(path, rows):
    with open(path, "w") as f:
        for r in rows:
            f.write(json.dumps(r) + "\n")
    return path


def page_state(browser):
    return browser.evaluate("JSON.stringify(Object.assign({}, document.body.dataset))")


def open_page(browser, path, name, query=""):
    """Loads a page, waits for its scene; checks status and console. Returns its data-* state."""
    browser.console_errors.clear()
    browser.open(path, query)
    ready = browser.wait_for("document.body.dataset.status !== 'loading'", 30)
    state = json.loads(page_state(browser))
    check(ready and state.get("status") == "ready", f"{name}: scene ready ({state.get('status')})")
    check(state.get("errors") == "0", f"{name}: no script errors on the page")
    check(not browser.console_errors, f"{name}: no console errors {browser.console_errors}")
    return state


def far(p, q):
    """Two pixels differ by more than 24 in a channel."""
    return max(abs(a - b) for a, b in zip(p, q)) > 24


def view_rect(browser):
    """The 3-D view's box on the page, in CSS pixels."""
    return browser.evaluate("JSON.parse(JSON.stringify(document.getElementById('view').getBoundingClientRect()))")


def nonblank_robot(browser, png_path, name):
    """The screenshot is not blank where the robot is: in the robot's box on the page, at least
    a twentieth of the pixels differ from the same view with the robot (and its ghosts) hidden,
    and from the background colour."""
    box = browser.evaluate("lazyboeView.robotScreenBox()")
    width, height, shown = chromium.read_png(browser.screenshot(png_path))
    browser.evaluate("lazyboeView.showRobots(false)")
    hidden = chromium.read_png(browser.screenshot(png_path + ".without-robot.png"))[2]
    browser.evaluate("lazyboeView.showRobots(true)")
    os.remove(png_path + ".without-robot.png")
    x0, y0 = max(0, int(box["x0"])), max(0, int(box["y0"]))
    x1, y1 = min(width, int(math.ceil(box["x1"]))), min(height, int(math.ceil(box["y1"])))
    check(x1 - x0 > 20 and y1 - y0 > 20, f"{name}: robot's box on screen {box}")
    points = [(x, y) for y in range(y0, y1, 2) for x in range(x0, x1, 2)]
    robot = sum(1 for x, y in points if far(shown[y][x], hidden[y][x]) and far(shown[y][x], BACKGROUND))
    share = robot / max(1, len(points))
    check(share > 0.05, f"{name}: the robot covers {share:.0%} of its box ({png_path})")


def view_pixels(browser, png_path):
    """The 3-D view's pixels in a screenshot taken after at least one more frame was drawn."""
    frames = browser.evaluate("lazyboeView.frameStats().frames")
    browser.wait_for(f"lazyboeView.frameStats().frames > {frames + 1}", 10)
    rect = view_rect(browser)
    pixels = chromium.read_png(browser.screenshot(png_path))[2]
    x0, y0, x1, y1 = (int(rect[k]) for k in ("left", "top", "right", "bottom"))
    return [row[x0:x1] for row in pixels[y0:y1]]


def differing_share(a, b):
    """Share of the pixels that are far() apart."""
    differing = sum(1 for ra, rb in zip(a, b) for p, q in zip(ra, rb) if far(p, q))
    return differing / max(1, sum(len(r) for r in a))


def drag(browser, dx):
    """A left-button drag across the view's centre: OrbitControls turns the camera."""
    rect = view_rect(browser)
    x, y = (rect["left"] + rect["right"]) / 2, (rect["top"] + rect["bottom"]) / 2
    mouse = lambda kind, px, buttons: browser.call("Input.dispatchMouseEvent", {  # noqa: E731
        "type": kind, "x": px, "y": y, "button": "left", "buttons": buttons, "clickCount": 1})
    mouse("mousePressed", x, 1)
    for k in range(1, 9):
        mouse("mouseMoved", x + dx * k / 8, 1)
    mouse("mouseReleased", x + dx, 0)


def cached_equals_direct(browser, page, out_dir):
    """The still layers drawn once and reused (the default with a software renderer) give the
    picture that drawing everything every frame gives, before and after the camera is turned
    (the cache is redrawn when the view changes)."""
    pictures = {}
    for cache in ("0", "1"):
        open_page(browser, page, f"page with cache={cache}", f"cache={cache}")
        check(browser.evaluate("lazyboeView.stillLayersCached") == (cache == "1"),
              f"cache={cache}: the still layers are {'' if cache == '1' else 'not '}cached")
        png = os.path.join(out_dir, f"cache{cache}.png")
        before = view_pixels(browser, png)
        drag(browser, 120)
        pictures[cache] = (before, view_pixels(browser, png))
        os.remove(png)
    turned = differing_share(*pictures["1"])
    check(turned > 0.05, f"dragging turned the cached view ({turned:.1%} of the pixels changed)")
    for i, when in enumerate(("before", "after")):
        share = differing_share(pictures["0"][i], pictures["1"][i])
        check(share < 0.002, f"cached and direct drawing agree {when} the camera turned "
              f"({share:.3%} of the pixels differ)")


def compare_fk(browser, bin_dir, configurations):
    """Every link's pose in the page against lazyboe-robot fk, to 1e-6."""
    worst = 0.0
    for q in configurations:
        page = browser.evaluate(f"lazyboeView.linkPoses({json.dumps(q)})")
        for link in page:
            tool = json.loads(run([os.path.join(bin_dir, "lazyboe-robot"), "fk", "--q",
                                   ",".join(repr(v) for v in q), "--link", link["link"]]))
            dp = max(abs(a - b) for a, b in zip(link["position"], tool["position"]))
            sign = 1 if sum(a * b for a, b in zip(link["quaternion"], tool["quaternion"])) >= 0 else -1
            dq = max(abs(sign * a - b) for a, b in zip(link["quaternion"], tool["quaternion"]))
            worst = max(worst, dp, dq)
    check(worst <= 1e-6, f"page forward kinematics = lazyboe-robot fk at {len(configurations)} "
          f"configurations, every link (largest difference {worst:.1e})")


def rotate(quaternion, v):
    """v rotated by the unit quaternion [w, x, y, z]."""
    w, x, y, z = quaternion
    u = (x, y, z)
    t = [2 * (u[1] * v[2] - u[2] * v[1]), 2 * (u[2] * v[0] - u[0] * v[2]), 2 * (u[0] * v[1] - u[1] * v[0])]
    return [v[i] + w * t[i] + (u[(i + 1) % 3] * t[(i + 2) % 3] - u[(i + 2) % 3] * t[(i + 1) % 3])
            for i in range(3)]


def task_page(bin_dir, out_dir):
    """A pose goal with a payload (line 1) and a goal set of a joint, a position and a pose goal
    (line 2), as issue 29's queries have them."""
    tool = os.path.join(bin_dir, "lazyboe-view")
    pose = {"pose": {"position": [0.4, 0.1, 0.5], "orientation": [0, 1, 0, 0]}, "position_tolerance": 0.02}
    queries = write_lines(os.path.join(out_dir, "task-queries.jsonl"), [
        {"id": "pose", "start": READY, "goal": pose, "payload": {"mass": 2.0, "com": [0, 0, 0.08]}},
        {"id": "set", "start": OTHER, "goal": [{"q": THIRD}, {"position": [0.3, -0.3, 0.4]}, pose]}])
    results = write_lines(os.path.join(out_dir, "task-results.jsonl"), [
        trajectory_result("pose", 1, READY, OTHER), trajectory_result("set", 2, OTHER, THIRD)])
    page = os.path.join(out_dir, "task.html")
    run([tool, "--results", results, "--queries", queries, "--out", page])
    return page


def check_task_page(browser, bin_dir, page):
    """Goal frames and goal sets drawn; the payload box at the tip's centre of mass (fk)."""
    open_page(browser, page, "task page")
    browser.evaluate("lazyboeView.select('trajectory', 0)")
    view = json.loads(browser.evaluate("JSON.stringify(lazyboeView.goalView())"))
    tip = json.loads(run([os.path.join(bin_dir, "lazyboe-robot"), "fk", "--q", ",".join(map(repr, READY))]))
    at = [p + d for p, d in zip(tip["position"], rotate(tip["quaternion"], [0, 0, 0.08]))]
    check(view["axes"] == 1 and view["spheres"] == 1 and view["ghosts"] == 0,
          f"task page: a pose goal is drawn as its frame and tolerance sphere ({view})")
    check(view["payload"] is not None and max(abs(a - b) for a, b in zip(view["payload"], at)) < 1e-6,
          f"task page: the payload box sits at the tip's centre of mass at the start ({view['payload']} vs {at})")
    browser.evaluate("lazyboeView.select('trajectory', 1)")
    view = json.loads(browser.evaluate("JSON.stringify(lazyboeView.goalView())"))
    check(view == {"ghosts": 1, "spheres": 2, "axes": 1, "payload": None},
          f"task page: every member of a goal set is drawn, no payload without one ({view})")
    check(not browser.console_errors, f"task page: no console errors {browser.console_errors}")


def obstacles_in(env_path):
    with open(env_path) as f:
        env = json.load(f)
    return len(env.get("obstacles", env.get("objects", [])))


def scene_with_files(out_dir):
    """table.json with a box as an OBJ mesh and a point cloud inline (issue 26's obstacle types)."""
    with open(os.path.join(SOURCE, "data", "environments", "table.json")) as f:
        scene = json.load(f)
    corners = [(x, y, z) for x in (-0.05, 0.05) for y in (-0.05, 0.05) for z in (-0.05, 0.05)]
    faces = [(1, 2, 4), (1, 4, 3), (5, 7, 8), (5, 8, 6), (1, 5, 6), (1, 6, 2),
             (3, 4, 8), (3, 8, 7), (1, 3, 7), (1, 7, 5), (2, 6, 8), (2, 8, 4)]
    obj = os.path.join(out_dir, "box.obj")
    with open(obj, "w") as f:
        f.writelines(f"v {x} {y} {z}\n" for x, y, z in corners)
        f.writelines(f"f {a} {b} {c}\n" for a, b, c in faces)
    rng = random.Random(5)
    points = [[0.45 + 0.1 * rng.random(), -0.35 + 0.1 * rng.random(), 0.3 + 0.1 * rng.random()]
              for _ in range(300)]
    scene["name"] = "files"
    scene["objects"] += [{"name": "box", "type": "mesh", "file": obj, "position": [0.5, 0.3, 0.35]},
                         {"name": "cloud", "type": "points", "points": points, "resolution": 0.02}]
    path = os.path.join(out_dir, "files.json")
    with open(path, "w") as f:
        json.dump(scene, f)
    return path, len(scene["objects"])


def main():
    bin_dir, out_dir = sys.argv[1], sys.argv[2]
    binary = chromium.find_chromium()
    if not binary:
        print("SKIPPED: Chromium is not installed (scripts/install-deps.sh installs Debian's chromium)")
        return 77
    os.makedirs(out_dir, exist_ok=True)
    tool = os.path.join(bin_dir, "lazyboe-view")

    # Inputs: three trajectories, one failed query, their queries, a small analysed bundle.
    bundle = os.path.join(out_dir, "bundle.h5")
    run([os.path.join(bin_dir, "lazyboe-build"), "--out", bundle, "--edges", "200", "--seed", "2",
         "--force", "--quiet"])
    run([os.path.join(bin_dir, "lazyboe-perturb"), "--bundle", bundle, "--perturbations", "2", "--quiet"])
    results = write_lines(os.path.join(out_dir, "results.jsonl"), [
        trajectory_result("a", 1, READY, OTHER), trajectory_result("b", 2, OTHER, THIRD),
        trajectory_result("c", 3, THIRD, READY), failed_result("d", 4, "no bundle coverage of the goal")])
    queries = write_lines(os.path.join(out_dir, "queries.jsonl"), [
        {"id": i, "start": s, "goal": {"q": g, "tolerance": 0.1}}
        for i, s, g in (("a", READY, OTHER), ("b", OTHER, THIRD), ("c", THIRD, READY), ("d", OTHER, READY))])
    main_page = os.path.join(out_dir, "view.html")
    run([tool, "--results", results, "--queries", queries, "--bundle", bundle, "--out", main_page])
    only_failed = os.path.join(out_dir, "failed.html")
    run([tool, "--results", write_lines(os.path.join(out_dir, "failed.jsonl"),
                                        [failed_result("d", 4, "search exhausted")]),
         "--queries", queries, "--out", only_failed])
    files_scene, files_obstacles = scene_with_files(out_dir)
    files_page = os.path.join(out_dir, "files.html")
    run([tool, "--results", results, "--queries", queries, "--env", files_scene, "--out", files_page])
    goals_page = task_page(bin_dir, out_dir)
    ur5_home, ur5_other = [0, -1.57, 1.57, -1.57, -1.57, 0], [0.5, -1.2, 1.3, -1.8, -1.4, 0.4]
    ur5_page = os.path.join(out_dir, "ur5.html")
    run([tool, "--robot", "ur5", "--results", write_lines(os.path.join(out_dir, "ur5.jsonl"), [
        trajectory_result("u", 1, ur5_home, ur5_other)]), "--out", ur5_page])
    ur5v_config, ur5v_visuals = ur5_with_visuals(out_dir)
    ur5v_page = os.path.join(out_dir, "ur5v.html")
    ur5v_run = subprocess.run([tool, "--robot", ur5v_config, "--results", os.path.join(out_dir, "ur5.jsonl"),
                               "--out", ur5v_page], capture_output=True, text=True)
    check(ur5v_run.returncode == 0 and f"({ur5v_visuals} visuals)" in ur5v_run.stdout
          and "warning" in ur5v_run.stderr and "gone.dae" in ur5v_run.stderr
          and "the link is drawn from its collision geometry" in ur5v_run.stderr,
          f"UR5 with visuals: {ur5v_visuals} read, the missing one a warning ({ur5v_run.stdout.strip()} "
          f"{ur5v_run.stderr.strip()})")
    no_trajectories = os.path.join(out_dir, "none.html")
    bare = trajectory_result("a", 1, READY, OTHER)
    del bare["trajectory"]
    run([tool, "--results", write_lines(os.path.join(out_dir, "none.jsonl"), [bare]),
         "--out", no_trajectories])

    env = os.path.join(SOURCE, "data", "environments", "table.json")
    with chromium.Chromium(binary, 960, 600) as browser:
        state = open_page(browser, main_page, "main page")
        check(state.get("trajectories") == "3" and state.get("failures") == "1",
              f"main page: 3 trajectories and 1 failed query loaded ({state})")
        check(int(state.get("robotShapes", 0)) > 0, "main page: robot shapes loaded")
        check(state.get("obstacles") == str(obstacles_in(env)), "main page: every obstacle of table.json")
        check(state.get("bundlePoints") == "400", "main page: 400 bundle points (200 edges)")
        text = browser.evaluate("document.body.innerText")
        check("no bundle coverage of the goal" in text, "main page: the failure reason is shown")
        check("a (lazysp, line 1): success, cost 1.00, duration 1.00 s" in text and "edges 3 5" in text,
              "main page: the selected trajectory's id, planner, line, cost, duration and edges are shown")
        nonblank_robot(browser, os.path.join(out_dir, "viewer.png"), "main page")
        check(browser.evaluate("lazyboeView.pathsOnScreen()") == 1,
              "main page: the default camera frames every planned path")
        check(browser.evaluate("lazyboeView.bundleShown()") is False,
              "main page: the bundle sample is hidden while there are trajectories to look at")
        browser.evaluate("document.getElementById('show-bundle').click()")
        check(browser.evaluate("lazyboeView.bundleShown()") is True, "main page: its toggle shows it")
        rng = random.Random(17)
        configurations = [READY, OTHER, THIRD] + [[rng.uniform(-2.5, 2.5) for _ in range(7)] for _ in range(2)]
        compare_fk(browser, bin_dir, configurations)
        browser.evaluate("lazyboeView.play()")
        check(browser.wait_for("lazyboeView.frameStats().frames > 10", 20), "main page: plays (frames drawn)")
        check(not browser.console_errors, f"main page: no console errors while playing {browser.console_errors}")
        # The harness sees errors when there are some (so "no console errors" above means it).
        browser.evaluate("console.error('probe'); setTimeout(() => { throw new Error('thrown probe'); }, 0)")
        for _ in range(50):  # each call also collects the events that came meanwhile
            if len(browser.console_errors) >= 2:
                break
            browser.evaluate("1")
            time.sleep(0.02)
        check(browser.wait_for("document.body.dataset.errors === '1' && !document.getElementById('errors').hidden", 5),
              "an uncaught exception is shown on the page and counted in data-errors")
        check(any("probe" in e for e in browser.console_errors) and
              any("thrown probe" in e for e in browser.console_errors),
              f"console errors and uncaught exceptions are caught by the test ({browser.console_errors})")
        browser.console_errors.clear()

        cached_equals_direct(browser, main_page, out_dir)

        state = open_page(browser, files_page, "mesh and point-cloud page")
        types = state.get("obstacleTypes", "").split()
        check(state.get("obstacles") == str(files_obstacles) and "mesh" in types and "cells" in types,
              f"mesh and point-cloud page: every obstacle, the mesh and the cloud's cells drawn ({types})")
        nonblank_robot(browser, os.path.join(out_dir, "files.png"), "mesh and point-cloud page")

        check_task_page(browser, bin_dir, goals_page)

        state = open_page(browser, ur5_page, "UR5 page")
        check(state.get("robotMeshes") == "7" and state.get("robotShapes") == "8",
              f"UR5 page: its 7 mesh links drawn as their meshes, the 8th shape as it is ({state})")
        nonblank_robot(browser, os.path.join(out_dir, "ur5.png"), "UR5 page")

        state = open_page(browser, ur5v_page, "UR5 page with visuals")
        check(state.get("robotVisuals") == str(ur5v_visuals) and state.get("robotShapes") == "8",
              f"UR5 page with visuals: every readable visual drawn, the base from its collision mesh ({state})")
        nonblank_robot(browser, os.path.join(out_dir, "ur5v.png"), "UR5 page with visuals")

        state = open_page(browser, only_failed, "failed-only page")
        text = browser.evaluate("document.body.innerText")
        check(state.get("failures") == "1" and "search exhausted" in text,
              "failed-only page: the failure and its reason are shown")
        check("No trajectories" in text, "failed-only page: says there is no trajectory")
        nonblank_robot(browser, os.path.join(out_dir, "failed.png"), "failed-only page (start ghost)")

        state = open_page(browser, no_trajectories, "no-trajectory page")
        text = browser.evaluate("document.body.innerText")
        check("carry no trajectory" in text and state.get("trajectories") == "0",
              "no-trajectory page: says the results carry no trajectory")
        nonblank_robot(browser, os.path.join(out_dir, "none.png"), "no-trajectory page")

    print(f"{len(failures)} failed" if failures else "all passed")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main())
