#!/usr/bin/env python3
"""Plans one query on a bundle with the Python module and plots its joint trajectory.

    make demo                                    # builds build/demo/bundle.h5
    PYTHONPATH=build/python /usr/bin/python3 examples/plot_trajectory.py \
        --bundle build/demo/bundle.h5 --out trajectory.png

The query is the first line of data/queries/table-demo.jsonl unless --query says otherwise
(any line of the query format, as a JSON string).
"""

import argparse
import json
import pathlib
import sys

import matplotlib

matplotlib.use("Agg")  # files only, no display needed
import matplotlib.pyplot as plt  # noqa: E402

import lazyboe  # noqa: E402

DEMO_QUERIES = pathlib.Path(lazyboe.data_dir()) / "queries" / "table-demo.jsonl"


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--bundle", default="build/demo/bundle.h5", help="bundle file (HDF5)")
    ap.add_argument("--out", default="trajectory.png", help="PNG to write")
    ap.add_argument("--query", help="a query as JSON (default: the demo batch's first)")
    ap.add_argument("--planner", help="planner instead of the query's")
    args = ap.parse_args()

    query = json.loads(args.query or DEMO_QUERIES.read_text().splitlines()[0])
    if args.planner:
        query["planner"] = args.planner
    session = lazyboe.PlanningSession(args.bundle)
    result = session.plan_many([query])[0]
    if not result.success:
        print(f"{query.get('id', 'query')}: no solution ({result.failure})", file=sys.stderr)
        return 1
    traj = result.trajectory
    print(f"{result.planner}: solved in {result.time_to_first_solution:.3f} s, "
          f"cost {result.best_cost:.3f} rad, {traj.duration:.2f} s of motion, "
          f"{len(result.edges)} edges")

    fig, (ax_q, ax_dq) = plt.subplots(2, 1, sharex=True, figsize=(8, 6))
    for j, name in enumerate(session.robot.joint_names):
        ax_q.plot(traj.t, traj.q[:, j], label=name)
        ax_dq.plot(traj.t, traj.dq[:, j])
    ax_q.set_ylabel("q (rad)")
    ax_dq.set_ylabel("dq (rad/s)")
    ax_dq.set_xlabel("t (s)")
    ax_q.legend(fontsize="small", ncol=4)
    ax_q.set_title(f"{query.get('id', '')}: {result.planner}, cost {result.best_cost:.3f} rad")
    fig.tight_layout()
    fig.savefig(args.out, dpi=100)
    print(f"wrote {args.out}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
