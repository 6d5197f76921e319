#!/usr/bin/env python3
"""The viewer's targets (issue 17, docs/performance.md): a page of a 100-trajectory results file
and a 20,000-point bundle sample, opened in headless Chromium; its load time (the page's
performance.now() when the scene is ready: from navigation start, inline scripts and data
parsed, scene built, first frame drawn) and its frame rate while playing (the page's own frame
timer: intervals between requestAnimationFrame callbacks).

usage: viewer-perf.py BIN_DIR WORK_DIR [--runs 3] [--seconds 5] [--size 1280x800]
WORK_DIR keeps the bundle (10,000 edges), the results and the page between runs."""

import argparse
import json
import os
import statistics
import subprocess
import sys
import time

HERE = os.path.dirname(os.path.abspath(__file__))
sys.path.insert(0, os.path.join(os.path.dirname(HERE), "tests", "viewer"))
import chromium  # noqa: E402


def run(args):
    subprocess.run(args, check=True, stdout=subprocess.DEVNULL)


def inputs(bin_dir, work):
    """A 10,000-edge analysed bundle and 100 lazysp results with inline trajectories."""
    bundle = os.path.join(work, "bundle.h5")
    if not os.path.exists(bundle):
        run([os.path.join(bin_dir, "lazyboe-build"), "--out", bundle, "--edges", "10000",
             "--theta", "0.45", "--seed", "4", "--quiet"])
        run([os.path.join(bin_dir, "lazyboe-perturb"), "--bundle", bundle, "--perturbations", "4", "--quiet"])
    results = os.path.join(work, "results.jsonl")
    if not os.path.exists(results):
        queries = os.path.join(work, "queries.jsonl")
        run([sys.executable, os.path.join(HERE, "make-queries.py"), queries, "100", "5",
             "--planners", "lazysp", "--budget", "2", "--tool", os.path.join(bin_dir, "lazyboe-robot")])
        run([os.path.join(bin_dir, "lazyboe-query"), "--bundle", bundle, "--queries", queries,
             "--out", results, "--trajectories", "inline", "--jobs", "2", "--sim-threads", "1", "--quiet"])
    page = os.path.join(work, "view.html")
    run([os.path.join(bin_dir, "lazyboe-view"), "--results", results, "--bundle", bundle,
         "--bundle-points", "20000", "--out", page])
    return page


def tree_cpu_seconds(root):
    """User + system CPU time of a process and all its descendants (/proc), s."""
    parent, cpu = {}, {}
    for entry in os.listdir("/proc"):
        if not entry.isdigit():
            continue
        try:
            with open(f"/proc/{entry}/stat") as f:
                fields = f.read().rsplit(")", 1)[1].split()
        except OSError:
            continue
        parent[int(entry)] = int(fields[1])
        cpu[int(entry)] = (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")
    total, todo = 0.0, [root]
    while todo:
        pid = todo.pop()
        total += cpu.get(pid, 0.0)
        todo += [child for child, p in parent.items() if p == pid]
    return total


def measure(binary, page, width, height, seconds, query):
    with chromium.Chromium(binary, width, height) as browser:
        browser.open(page, query)
        if not browser.wait_for("document.body.dataset.status === 'ready'", 60):
            raise RuntimeError("page not ready: " + str(browser.console_errors))
        state = json.loads(browser.evaluate("JSON.stringify(Object.assign({}, document.body.dataset))"))
        browser.evaluate("lazyboeView.play()")
        time.sleep(1)
        browser.evaluate("lazyboeView.resetFrameStats()")
        cpu0, frames0 = tree_cpu_seconds(browser.proc.pid), browser.evaluate("lazyboeView.frameStats().frames")
        time.sleep(seconds)
        stats = browser.evaluate("lazyboeView.frameStats()")
        cpu1 = tree_cpu_seconds(browser.proc.pid)
        # CPU time the whole browser (every process) spends per frame drawn: less dependent on
        # the machine's load than the frame rate; 2 cores give 33 ms of CPU per 60 fps frame.
        stats["cpu_ms_per_frame"] = 1000 * (cpu1 - cpu0) / max(1, stats["frames"] - frames0)
        stats["load_ms"] = float(state["loadMs"])
        stats["state"] = state
        stats["renderer"] = browser.evaluate("lazyboeView.renderer")
        stats["errors"] = list(browser.console_errors)
        return stats


def main():
    p = argparse.ArgumentParser()
    p.add_argument("bin_dir")
    p.add_argument("work")
    p.add_argument("--runs", type=int, default=3)
    p.add_argument("--seconds", type=float, default=5)
    p.add_argument("--size", default="1280x800")
    p.add_argument("--query", default="", help='URL query of the page, e.g. "scale=0.5"')
    a = p.parse_args()
    binary = chromium.find_chromium()
    if not binary:
        sys.exit("viewer-perf: Chromium is not installed (scripts/install-deps.sh)")
    os.makedirs(a.work, exist_ok=True)
    page = inputs(a.bin_dir, a.work)
    width, height = (int(v) for v in a.size.split("x"))
    runs = []
    for _ in range(a.runs):
        load = os.getloadavg()[0]
        s = measure(binary, page, width, height, a.seconds, a.query)
        s["load_average"] = load
        runs.append(s)
        print(f"load {s['load_ms']:.0f} ms, {s['fps']:.1f} fps (mean frame interval "
              f"{s['mean_interval_ms']:.1f} ms, p95 {s['p95_interval_ms']:.1f} ms, render call "
              f"{s['mean_render_ms']:.2f} ms); Chromium CPU time {s['cpu_ms_per_frame']:.1f} ms per frame, machine load average "
              f"{load:.2f}")
    st = runs[0]["state"]
    print(f"page {os.path.getsize(page) / 1e6:.2f} MB: {st['trajectories']} trajectories, "
          f"{st['bundlePoints']} bundle points, {st['robotShapes']} robot shapes, renderer "
          f"{runs[0]['renderer']}, {width}x{height}; console errors: {runs[0]['errors']}")
    print(f"median: load {statistics.median(r['load_ms'] for r in runs):.0f} ms, "
          f"{statistics.median(r['fps'] for r in runs):.1f} fps, Chromium CPU time "
          f"{statistics.median(r['cpu_ms_per_frame'] for r in runs):.1f} ms per frame")


if __name__ == "__main__":
    main()
