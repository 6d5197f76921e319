#!/usr/bin/env python3
"""The Python module's performance figures (docs/performance.md, "Python module"):

1. plan(): the per-call cost the module adds (a call that goes through everything but the
   planner: argument conversion, the query's JSON, parse_query, the GIL, a rejected problem's
   exception) against the median planning time of the demo batch; and the demo batch planned
   from Python against lazyboe-query on the same queries.
2. Two Python threads planning at once against one after the other (the same answers).
3. Vectorized forward kinematics and inverse dynamics over 100,000 states, per state, against
   bench_robot's BM_ForwardKinematics / BM_InverseDynamics run now on the same machine.

    PYTHONPATH=build/python /usr/bin/python3 python/bench/bench_module.py \
        --bundle build/demo/bundle.h5 --tools build/bin
"""

import argparse
import json
import pathlib
import statistics
import subprocess
import threading
import time

import numpy as np

import lazyboe


def demo_queries(budget):
    path = pathlib.Path(lazyboe.data_dir()) / "queries" / "table-demo.jsonl"
    queries = [json.loads(line) for line in path.read_text().splitlines() if line.strip()]
    for q in queries:
        q["budget"] = budget
        q["stop_at_first"] = True  # a deterministic answer, and time that is planning, not budget
    return queries


def call_overhead(session, queries, repeats):
    """Seconds per plan() call that ends before planning (the goal holds the start)."""
    q = queries[0]
    goal = {"q": q["start"], "tolerance": 0.1}
    times = []
    for _ in range(repeats):
        t = time.perf_counter()
        try:
            session.plan(q["start"], goal, planner=q["planner"], seed=1)
        except ValueError:
            pass
        times.append(time.perf_counter() - t)
    return statistics.median(times)


def python_batch(session, queries):
    times, results = [], []
    for q in queries:
        t = time.perf_counter()
        results.append(session.plan(**q))
        times.append(time.perf_counter() - t)
    return times, results


def tool_batch(tools, bundle, queries, workdir):
    path = workdir / "bench-queries.jsonl"
    path.write_text("".join(json.dumps(q) + "\n" for q in queries))
    t = time.perf_counter()
    out = subprocess.run([str(tools / "lazyboe-query"), "--bundle", str(bundle), "--queries",
                          str(path), "--sim-threads", "1", "--quiet"], check=True,
                         capture_output=True, text=True).stdout
    wall = time.perf_counter() - t
    path.unlink()
    return wall, [json.loads(line) for line in out.splitlines()]


def without_timings(d, drop=()):
    """A result line without its wall times (and the keys in `drop`)."""
    out = {k: v for k, v in d.items() if k != "time_to_first_solution" and k not in drop}
    if "post_processing" in out:
        out["post_processing"] = {k: v for k, v in out["post_processing"].items()
                                  if k not in ("seconds", "raw_seconds")}
    return out


def same_answers(results, lines):
    """Every field of the result lines but timings, id and line (the tool's have no trajectory)."""
    drop = ("line", "id", "trajectory")
    return all(without_timings(r.to_dict(), drop) == without_timings(line, drop)
               for r, line in zip(results, lines))


def threads_figure(session, queries):
    halves = [queries[0::2], queries[1::2]]
    t = time.perf_counter()
    sequential = [[session.plan(**q).to_dict() for q in h] for h in halves]
    t_seq = time.perf_counter() - t
    concurrent = [None, None]

    def run(k):
        concurrent[k] = [session.plan(**q).to_dict() for q in halves[k]]

    threads = [threading.Thread(target=run, args=(k,)) for k in range(2)]
    t, cpu = time.perf_counter(), time.process_time()
    for th in threads:
        th.start()
    for th in threads:
        th.join()
    t_par = time.perf_counter() - t
    cpu_share = (time.process_time() - cpu) / t_par  # up to 2 when both threads run at once
    same = all([without_timings(r) for r in a] == [without_timings(r) for r in b]
               for a, b in zip(sequential, concurrent))
    return t_seq, t_par, cpu_share, same


def cxx_benchmark(tools, name):
    out = subprocess.run([str(tools / "bench_robot"), f"--benchmark_filter=^{name}$",
                          "--benchmark_format=json", "--benchmark_repetitions=3",
                          "--benchmark_report_aggregates_only=true"],
                         check=True, capture_output=True, text=True).stdout
    for b in json.loads(out)["benchmarks"]:
        if b["name"].endswith("_median"):
            return b["real_time"] * {"ns": 1e-9, "us": 1e-6, "ms": 1e-3}[b["time_unit"]]
    raise RuntimeError(f"no median for {name}")


def vectorized(robot, n, repeats):
    rng = np.random.default_rng(1)
    q = rng.uniform(robot.lower, robot.upper, (n, robot.dof))
    dq = rng.uniform(-robot.velocity_limits, robot.velocity_limits, (n, robot.dof))
    ddq = rng.uniform(-robot.acceleration_limits, robot.acceleration_limits, (n, robot.dof))
    figures = {}
    for name, call in (("forward_kinematics", lambda: robot.forward_kinematics(q)),
                       ("inverse_dynamics", lambda: robot.inverse_dynamics(q, dq, ddq))):
        times = []
        for _ in range(repeats):
            t = time.perf_counter()
            call()
            times.append(time.perf_counter() - t)
        figures[name] = min(times) / n
    return figures


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--bundle", default="build/demo/bundle.h5")
    ap.add_argument("--tools", default="build/bin", type=pathlib.Path)
    ap.add_argument("--budget", type=float, default=10.0)
    ap.add_argument("--states", type=int, default=100000)
    args = ap.parse_args()
    session = lazyboe.PlanningSession(args.bundle)
    queries = demo_queries(args.budget)

    overhead = call_overhead(session, queries, 200)
    # The batch from Python and from the tool, alternately three times (the machine is
    # shared: the least of each is the least disturbed).
    python_walls, tool_walls, medians = [], [], []
    for _ in range(3):
        times, results = python_batch(session, queries)
        python_walls.append(sum(times))
        medians.append(statistics.median(times))
        tool_wall, tool_lines = tool_batch(args.tools, args.bundle, queries,
                                           pathlib.Path(args.bundle).parent)
        tool_walls.append(tool_wall)
    median = min(medians)
    print(f"plan(): per-call cost without planning {overhead * 1e6:.0f} us; median plan() "
          f"{median * 1e3:.1f} ms over {len(queries)} demo queries: "
          f"{100 * overhead / median:.3f} % of it")
    print(f"demo batch (least of 3): Python {min(python_walls):.2f} s planning "
          f"(+ {session.load_seconds:.3f} s load), lazyboe-query {min(tool_walls):.2f} s wall "
          f"including its load and start-up; successes {sum(r.success for r in results)} vs "
          f"{sum(line['success'] for line in tool_lines)}; the same answers: "
          f"{same_answers(results, tool_lines)}")

    t_seq, t_par, cpu_share, same = threads_figure(session, queries)
    print(f"two threads: {t_par:.2f} s at once vs {t_seq:.2f} s one after the other "
          f"({t_seq / t_par:.2f}x; CPU time / wall time at once {cpu_share:.2f}); the same "
          f"answers: {same}")

    robot = lazyboe.Robot()
    figures = vectorized(robot, args.states, 5)
    for name, bench in (("forward_kinematics", "BM_ForwardKinematics"),
                        ("inverse_dynamics", "BM_InverseDynamics")):
        cxx = cxx_benchmark(args.tools, bench)
        print(f"{name} over {args.states} states: {figures[name] * 1e6:.3f} us per state; "
              f"{bench} {cxx * 1e6:.3f} us ({figures[name] / cxx:.2f}x)")


if __name__ == "__main__":
    main()
