#!/usr/bin/env bash
# Bring your own robot, on the shipped UR5: from its URDF to planned trajectories and a viewer
# page. The config is made by `lazyboe-robot init` (no hand edits), then the pipeline of the
# Panda's demo runs on it: a small edge bundle on table.json in a table-top region, its
# perturbation analysis, a batch of random queries answered by lazysp and RRT, and the viewer.
set -euo pipefail
build=${1:-build}
bin="$build/bin"
out=${2:-$build/demo-ur5}  # the outputs (a test gives its own folder)
mkdir -p "$out"
out=$(cd "$out" && pwd)  # absolute: the bundle records its robot config's path
# The UR5's table-top work: shoulder turned at most 0.8 rad from the table, elbow up, the tool
# pointing down (around q = 0, -1.57, 1.57, -1.57, -1.57, 0); 76% of it is free of collision.
region="-0.8:0.8,-2.0:-1.0,0.9:2.2,-2.4:-0.8,-2.2:-0.9,-1.0:1.0"

echo "== 1. Robot config from the URDF: lazyboe-robot init on data/robots/ur5/ur5.urdf"
echo "   (limits from the URDF, documented defaults for the rest, gains computed from the model"
echo "    and checked by a step on every joint, allowed pairs by sampling: no hand edits)"
"$bin/lazyboe-robot" init --urdf data/robots/ur5/ur5.urdf --package-path data/robots/ur5 \
  --tip-link tool0 --name ur5 --convex-links upper_arm_link --out "$out/ur5.json" 2>&1 |
  tail -n 4 | sed 's/^/   /'
"$bin/lazyboe-robot" --robot "$out/ur5.json" info | sed -n '1,4p'
printf '   tool at the table-top pose: '
"$bin/lazyboe-robot" --robot "$out/ur5.json" fk --q 0,-1.57,1.57,-1.57,-1.57,0
echo
echo "== 2. Edge bundle: 3000 valid rollouts of the UR5's dynamics on table.json"
echo "   (look at: the valid share and 'edge starts within theta' at the end, as for the Panda)"
"$bin/lazyboe-build" --robot "$out/ur5.json" --env table --region="$region" --out "$out/bundle.h5" \
  --edges 3000 --theta 0.45 --seed 1 --force
"$bin/lazyboe-build" --inspect "$out/bundle.h5" | grep -E '^(bundle|  robot|  edges|  region)|within theta'
echo
echo "== 3. Perturbation analysis: 8 perturbed re-simulations per edge"
echo "   (look at: P_lazy_prop and P_collision, the figures lazysp and LazyBoE plan with)"
"$bin/lazyboe-perturb" --bundle "$out/bundle.h5" --perturbations 8 | grep -E '^(perturbation|P_)'
echo
echo "== 4. Planning: 8 random problems of the region, start and goal 1.5 rad apart, x lazysp and RRT (2 s each)"
echo "   (look at: success, and lazysp's median time to first solution against RRT's)"
python3 scripts/make-queries.py "$out/queries.jsonl" 8 3 --robot "$out/ur5.json" \
  --region="$region" --box region --clearance 0.005 --min-separation 1.5 \
  --planners lazysp,rrt --budget 2 --tool "$bin/lazyboe-robot"
"$bin/lazyboe-query" --bundle "$out/bundle.h5" --queries "$out/queries.jsonl" \
  --out "$out/results.jsonl" --jobs 2 --trajectories csv --trajectory-dir "$out/trajectories"
python3 - "$out/results.jsonl" <<'PY'
import collections, json, sys
found = collections.Counter(r.get("found_by") for r in map(json.loads, open(sys.argv[1]))
                            if r.get("planner") == "lazysp" and r.get("success"))
print("   lazysp's answers: " + ", ".join(f"{n} {k}" for k, n in sorted(found.items())) +
      " (direct: the straight command from start to goal; bundle: a search over the edges)")
PY
echo

echo "== 5. Viewer: the UR5 (its collision meshes and capsules), the table and the trajectories"
echo "   (look at: pick a query and play it; RRT's failures are listed with their reason)"
"$bin/lazyboe-view" --results "$out/results.jsonl" --queries "$out/queries.jsonl" \
  --bundle "$out/bundle.h5" --bundle-points 2000 --title "LazyBoE demo: the UR5 on table.json" \
  --out "$out/view.html"
echo
echo "demo-ur5: done (outputs in $out/); the viewer page: $(realpath "$out/view.html")"
