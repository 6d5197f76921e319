#!/usr/bin/env python3
"""Writes a batch of random planning queries (JSON Lines) whose start and goal are collision-free
configurations of a sub-box of the sampling region, checked with `lazyboe-robot check`.

usage: make-queries.py OUT.jsonl COUNT SEED [--env FILE] [--tolerance T] [--planners a,b]
                      [--box central|region] [--robot FILE] [--region lo:hi,...]
                      [--clearance M] [--blocked] [--min-separation R]

Any robot (its dof and sampling region from `lazyboe-robot info --json`).

--blocked keeps only pairs whose straight joint-space line collides in the scene (checked at
every 0.02 rad with lazyboe-robot check): problems a single straight command cannot solve. It
prints the share of candidate pairs that were blocked.

Candidates are drawn in rounds of 40 per problem (paired in the order drawn) until COUNT
problems are found, up to 25 rounds: a crowded scene leaves few free configurations and fewer
blocked pairs. The first round is the whole draw of earlier versions, so a set those could
draw comes out the same.
"""
import argparse, csv, json, math, os, random, subprocess, sys, tempfile

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))  # defaults from any folder
p = argparse.ArgumentParser()
p.add_argument("out"); p.add_argument("count", type=int); p.add_argument("seed", type=int)
p.add_argument("--env", default=os.path.join(ROOT, "data/environments/table.json"))
p.add_argument("--tolerance", type=float, default=0.3)
p.add_argument("--budget", type=float, default=2.0)
p.add_argument("--planners", default="lazyboe,boe,rrt,sst")
p.add_argument("--tool", default=os.path.join(ROOT, "build/bin/lazyboe-robot"))
p.add_argument("--robot", default=os.path.join(ROOT, "data/robots/panda.json"))
p.add_argument("--blocked", action="store_true",
               help="only pairs whose straight joint-space line collides in the scene")
p.add_argument("--min-separation", type=float, default=0.0,
               help="smallest joint-space distance between start and goal, rad")
p.add_argument("--box", choices=["central", "region"], default="central",
               help="central: the middle 60%% of the robot's sampling region (the Panda's "
               "table-top box, or another robot's joint range), where a small demo bundle is "
               "dense enough; region: the whole sampling region")
p.add_argument("--region", help="the bundle's region when it was built with lazyboe-build "
               "--region lo:hi,lo:hi,... (the same text); default: the robot config's")
p.add_argument("--clearance", type=float, default=0.03,
               help="smallest distance of a start or goal to any obstacle or other link, m")
a = p.parse_args()
# Any robot: its sampling region as the tools read it (the config's, else the joint limits).
info = json.loads(subprocess.run([a.tool, "--robot", a.robot, "info", "--json"], check=True,
                                 capture_output=True, text=True).stdout)
lo, hi = info["sampling_region"]["lower"], info["sampling_region"]["upper"]
if a.region:
    bounds = [b.split(":") for b in a.region.split(",")]
    if len(bounds) != info["dof"] or any(len(b) != 2 for b in bounds):
        sys.exit(f"make-queries: --region: expected {info['dof']} lo:hi pairs, one per joint")
    lo, hi = [float(b[0]) for b in bounds], [float(b[1]) for b in bounds]
if a.box == "central":  # rounded inwards to 0.05 rad (for the Panda: its former fixed box)
    def central(l, h):
        cl, ch = l + 0.2 * (h - l), h - 0.2 * (h - l)
        rl, rh = math.ceil(cl / 0.05 - 1e-9) * 0.05, math.floor(ch / 0.05 + 1e-9) * 0.05
        return (round(rl, 4), round(rh, 4)) if rl < rh else (cl, ch)  # too narrow to round
    lo, hi = (list(b) for b in zip(*(central(l, h) for l, h in zip(lo, hi))))
rng = random.Random(a.seed)


def check(configs, clearance=None):
    """lazyboe-robot check of each configuration: True where it is free (with `clearance`, m)."""
    clearance = a.clearance if clearance is None else clearance
    with tempfile.TemporaryDirectory() as d:
        inp, res = os.path.join(d, "in.csv"), os.path.join(d, "out.csv")
        with open(inp, "w") as f:
            f.write(",".join(f"q{i}" for i in range(1, len(configs[0]) + 1)) + "\n")
            f.writelines(",".join(map(str, q)) + "\n" for q in configs)
        subprocess.run([a.tool, "--robot", a.robot, "check", "--env", a.env, "--in", inp, "--out", res],
                       check=True, stderr=subprocess.DEVNULL)
        rows = list(csv.DictReader(open(res)))
    return [r["in_limits"] == "1" and r["self_collision"] == "0" and r["env_collision"] == "0"
            and float(r["min_distance"]) > clearance for r in rows]


def line_blocked(s, g):
    n = max(2, int(math.dist(s, g) / 0.02) + 1)
    line = [[s[i] + (g[i] - s[i]) * k / n for i in range(len(s))] for k in range(1, n)]
    return not all(check(line, clearance=-1))  # a collision (at the robot's margin), not 3 cm


# Candidates in rounds of 40 per problem, paired in the order drawn, until there are enough (a
# crowded scene leaves few free configurations, and few pairs with a blocked line): the first
# round is what a single draw gave, so sets drawn before rounds existed come out the same.
MAX_ROUNDS = 25
pairs, tried, blocked = [], 0, 0
for round_ in range(MAX_ROUNDS):
    cand = [[round(rng.uniform(l, h), 4) for l, h in zip(lo, hi)] for _ in range(40 * a.count)]
    free = [q for q, ok in zip(cand, check(cand)) if ok]
    for i in range(0, len(free) - 1, 2):
        if len(pairs) == a.count:
            break
        s, g = free[i], free[i + 1]
        if math.dist(s, g) < a.min_separation:
            continue
        tried += 1
        if a.blocked:
            if not line_blocked(s, g):
                continue
            blocked += 1
        pairs.append((s, g))
    if len(pairs) == a.count:
        break
    if round_ + 1 < MAX_ROUNDS:
        print(f"make-queries: {len(pairs)} of {a.count} problems after round {round_ + 1}; "
              "drawing more", file=sys.stderr)
if len(pairs) < a.count:
    sys.exit(f"make-queries: only {len(pairs)} of {a.count} problems found in {MAX_ROUNDS} rounds "
             f"of {40 * a.count} candidates; try another seed or scene")
if a.blocked:
    print(f"{blocked} of {tried} pairs tried had a blocked straight line "
          f"({100.0 * blocked / tried:.0f}%)", file=sys.stderr)
with open(a.out, "w") as f:
    for i, (s, g) in enumerate(pairs):
        for planner in a.planners.split(","):
            f.write(json.dumps({"id": f"p{i}-{planner}", "start": s,
                                "goal": {"q": g, "tolerance": a.tolerance},
                                "planner": planner, "budget": a.budget, "seed": 1}) + "\n")
print(f"wrote {a.count} problems x {len(a.planners.split(','))} planners to {a.out}", file=sys.stderr)
