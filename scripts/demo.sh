#!/usr/bin/env bash
# The main job on the bundled defaults. For now (the foundation stage) it shows the robot model
# at work: the description, forward kinematics, inverse dynamics with friction and collision
# checks on the bundled table environment.
set -euo pipefail
build=${1:-build}
bin="$build/bin"
out="$build/demo"
mkdir -p "$out"

echo "== lazyboe-robot info (data/robots/panda.json)"
"$bin/lazyboe-robot" info | sed -n '1,13p'
echo "   ..."
echo
echo "== forward kinematics of the flange"
for q in 0,0,0,0,0,0,0 0,-0.785,0,-2.356,0,1.571,0.785; do
  printf '   q = %-34s -> ' "$q"
  "$bin/lazyboe-robot" fk --q "$q"
done
echo
echo "== inverse dynamics with friction (data/examples/states.csv -> $out/torques.csv)"
"$bin/lazyboe-robot" torques --in data/examples/states.csv --out "$out/torques.csv"
paste -d' ' <(cut -d, -f1-7 data/examples/states.csv | sed 's/^/   q: /') <(sed 's/^/ -> tau: /' "$out/torques.csv") | column -t
echo
echo "== collision checks on data/environments/table.json (data/examples/configs.csv -> $out/check.csv)"
"$bin/lazyboe-robot" check --env data/environments/table.json --in data/examples/configs.csv --out "$out/check.csv"
paste -d, data/examples/configs.csv "$out/check.csv" | column -t -s, | sed 's/^/   /'
echo
echo "demo: done (outputs in $out/)"
