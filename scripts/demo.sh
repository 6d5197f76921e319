#!/usr/bin/env bash
# The main job on the bundled defaults: the robot model at work, then the whole pipeline on the
# default environment (table.json): a small edge bundle, its perturbation analysis, and the
# bundled sample batch answered by every planner, and a viewer page of it all.
set -euo pipefail
build=${1:-build}
bin="$build/bin"
out=${2:-$build/demo}  # the outputs (a test gives its own folder)
mkdir -p "$out"

echo "== 1. Robot model: data/robots/panda.json"
echo "   (the model every later step simulates: forward kinematics, inverse dynamics with friction,"
echo "    collision checks; lazyboe-robot does each for your own states and configurations)"
"$bin/lazyboe-robot" info | sed -n '1,4p'
printf '   flange at the ready pose: '
"$bin/lazyboe-robot" fk --q 0,-0.785,0,-2.356,0,1.571,0.785
"$bin/lazyboe-robot" torques --in data/examples/states.csv --out "$out/torques.csv" 2>/dev/null
echo "   inverse dynamics with friction of data/examples/states.csv (q rad, dq rad/s; ddq in the file; tau N m):"
paste -d' ' <(cut -d, -f1-7 data/examples/states.csv | sed 's/^/     q: /') \
  <(cut -d, -f8-14 data/examples/states.csv | sed 's/^/ dq: /') \
  <(awk -F, 'NR == 1 { print; next } { for (i = 1; i <= NF; i++) printf "%s%.2f", (i > 1 ? "," : ""), $i; print "" }' \
     "$out/torques.csv" | sed 's/^/ -> tau: /') | column -t
"$bin/lazyboe-robot" check --env data/environments/table.json --in data/examples/configs.csv --out "$out/check.csv" 2>/dev/null
echo "   collision checks on table.json of data/examples/configs.csv:"
paste -d, data/examples/configs.csv "$out/check.csv" | column -t -s, | sed 's/^/     /'
echo
# A demo-sized bundle: 6000 edges instead of 100000, so theta is raised from 0.35 to 0.45 to
# keep tens of neighbours per node (docs/bundle.md).
echo "== 2. Edge bundle: 6000 valid rollouts of the Panda's dynamics on table.json"
echo "   (look at: the share of valid rollouts, and 'edge starts within theta' at the end: how many"
echo "    edges a planner can take from a random state; tens is good, 'none' marks holes)"
"$bin/lazyboe-build" --out "$out/bundle.h5" --edges 6000 --theta 0.45 --seed 1 --force
echo
"$bin/lazyboe-build" --inspect "$out/bundle.h5" | sed -n '1,12p;/edge displacement/,/^coverage/p;/within theta/p' | grep -v '^coverage'
echo
echo "== 3. Perturbation analysis: 8 perturbed re-simulations per edge"
echo "   (look at: P_lazy_prop, how often an edge started up to theta away still ends near its"
echo "    stored end, and P_collision; LazyBoE trusts the edges whose product P_select is high)"
"$bin/lazyboe-perturb" --bundle "$out/bundle.h5" --perturbations 8
echo
echo "== 4. Planning: data/queries/table-demo.jsonl (6 problems x lazyboe, boe, rrt, sst, lazysp; 1 s each)"
echo "   (look at: success and the median time to first solution (TTFS): the bundle planners in"
echo "    milliseconds, RRT and SST, which simulate as they search, in tenths of a second)"
"$bin/lazyboe-query" --bundle "$out/bundle.h5" --queries data/queries/table-demo.jsonl \
  --out "$out/results.jsonl" --jobs 2 --trajectories csv --trajectory-dir "$out/trajectories"
echo "   results: $out/results.jsonl, trajectories: $out/trajectories/"
# The returned trajectories are post-processed (docs/execution.md): their execution against the
# planners' raw edge chains.
command -v python3 > /dev/null && python3 - "$out/results.jsonl" <<'PY'
import json, statistics, sys
rows = [json.loads(l) for l in open(sys.argv[1]) if l.strip()]
ok = [r for r in rows if r.get("success")]
if ok:
    m = lambda k: statistics.median(r[k] for r in ok)
    print(f"   execution (median over {len(ok)} trajectories): {m('duration'):.2f} s with "
          f"{m('stops'):.0f} stops, against {m('raw_duration'):.2f} s and {m('raw_stops'):.0f} "
          "stops for the raw edge chains (lazyboe-query --raw)")
PY
echo
echo "== 5. The same bundle in a scene it was not built in: a random cluttered table (make-scene.py clutter 7)"
echo "   (look at: no rebuild; the workspace index marks the edges the new objects may block, in"
echo "    milliseconds, and lazysp re-simulates every edge it returns in the new scene)"
# Any scene of the robot, given at query time: only collisions change, and every returned edge
# is simulated again in the query's scene. Problems whose straight joint-space line collides.
python3 scripts/make-scene.py clutter 7 "$out/clutter.json"
python3 scripts/make-queries.py "$out/clutter-queries.jsonl" 4 7 --env "$out/clutter.json" \
  --blocked --min-separation 0.6 --planners lazysp,rrt --budget 2 --tool "$bin/lazyboe-robot"
"$bin/lazyboe-query" --bundle "$out/bundle.h5" --queries "$out/clutter-queries.jsonl" \
  --env "$out/clutter.json" --out "$out/clutter-results.jsonl" --jobs 2
echo "   results: $out/clutter-results.jsonl (each says \"scene\": {\"name\": \"clutter-7\", ...})"
echo
echo "== 6. Viewer: robot, table, the trajectories above and a sample of the bundle, in 3-D"
echo "   (look at: pick a query, play its trajectory; the bundle sample is behind a checkbox)"
"$bin/lazyboe-view" --results "$out/results.jsonl" --queries data/queries/table-demo.jsonl \
  --bundle "$out/bundle.h5" --bundle-points 4000 --title "LazyBoE demo: table.json" --out "$out/view.html"
echo "   open in a browser (one self-contained file): $(realpath "$out/view.html")"
echo
echo "demo: done (outputs in $out/); the viewer page: $(realpath "$out/view.html")"
