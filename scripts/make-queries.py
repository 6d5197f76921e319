#!/usr/bin/env python3
"""Writes a batch of random planning queries (JSON Lines) whose start and goal are collision-free
configurations of a sub-box of the sampling region, checked with `lazyboe-robot check`.

usage: make-queries.py OUT.jsonl COUNT SEED [--env FILE] [--tolerance T] [--planners a,b]
                      [--box central|region] [--robot FILE]
"""
import argparse, csv, json, os, random, subprocess, sys, tempfile

p = argparse.ArgumentParser()
p.add_argument("out"); p.add_argument("count", type=int); p.add_argument("seed", type=int)
p.add_argument("--env", default="data/environments/table.json")
p.add_argument("--tolerance", type=float, default=0.3)
p.add_argument("--budget", type=float, default=2.0)
p.add_argument("--planners", default="lazyboe,boe,rrt,sst")
p.add_argument("--tool", default="build/bin/lazyboe-robot")
p.add_argument("--robot", default="data/robots/panda.json")
p.add_argument("--box", choices=["central", "region"], default="central",
               help="central: the middle of the Panda's region, where a small demo bundle is "
               "dense enough; region: the robot config's whole sampling region")
a = p.parse_args()
if a.box == "central":
    lo = [-0.6, -0.1, -0.35, -2.35, -0.35, 1.55, 0.35]
    hi = [0.6, 0.5, 0.35, -1.65, 0.35, 2.25, 1.25]
else:
    region = json.load(open(a.robot))["sampling_region"]
    lo, hi = region["lower"], region["upper"]
rng = random.Random(a.seed)
with tempfile.TemporaryDirectory() as d:
    cand = [[round(rng.uniform(l, h), 4) for l, h in zip(lo, hi)] for _ in range(8 * a.count)]
    inp, res = os.path.join(d, "in.csv"), os.path.join(d, "out.csv")
    with open(inp, "w") as f:
        f.write(",".join(f"q{i}" for i in range(1, 8)) + "\n")
        f.writelines(",".join(map(str, q)) + "\n" for q in cand)
    subprocess.run([a.tool, "--robot", a.robot, "check", "--env", a.env, "--in", inp, "--out", res], check=True,
                   stderr=subprocess.DEVNULL)
    rows = list(csv.DictReader(open(res)))
free = [q for q, r in zip(cand, rows)
        if r["in_limits"] == "1" and r["self_collision"] == "0" and r["env_collision"] == "0"
        and float(r["min_distance"]) > 0.03]
pairs = [(free[2 * i], free[2 * i + 1]) for i in range(a.count)]
with open(a.out, "w") as f:
    for i, (s, g) in enumerate(pairs):
        for planner in a.planners.split(","):
            f.write(json.dumps({"id": f"p{i}-{planner}", "start": s,
                                "goal": {"q": g, "tolerance": a.tolerance},
                                "planner": planner, "budget": a.budget, "seed": 1}) + "\n")
print(f"wrote {a.count} problems x {len(a.planners.split(','))} planners to {a.out}", file=sys.stderr)
