#!/usr/bin/env bash
# The installed package as a user meets it: `cmake --install` of this build into a fresh
# prefix, the out-of-tree example (examples/plan_one_query) configured with find_package(lazyboe)
# against that prefix, built, and run on a small bundle made by the installed tools.
set -euo pipefail
build=$1 source=$2
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT
cmake --install "$build" --prefix "$work/prefix" > "$work/install.log"
test -f "$work/prefix/include/lazyboe/planning/registry.h"
test -f "$work/prefix/lib/cmake/lazyboe/lazyboeConfig.cmake"
test ! -e "$work/prefix/include/lazyboe/bundle/hdf5_handle.h"   # internal headers stay out
# The data stands alone (issue 30): installed, and what the installed tools read, from any
# folder, whatever the source tree holds.
test -f "$work/prefix/share/lazyboe/robots/panda.json"
test -f "$work/prefix/share/lazyboe/environments/shelf.json"
test -x "$work/prefix/share/lazyboe/scripts/plot-bench.py"
info=$(cd "$work" && env -u LAZYBOE_DATA_DIR "$work/prefix/bin/lazyboe-robot" info)
case "$info" in
  *"config $work/prefix/share/lazyboe/robots/panda.json"*) ;;
  *) echo "FAIL: the installed lazyboe-robot reads its data elsewhere: $info"; exit 1 ;;
esac
cmake -S "$source/examples/plan_one_query" -B "$work/example" -DCMAKE_PREFIX_PATH="$work/prefix" \
  > "$work/configure.log" || { cat "$work/configure.log"; exit 1; }
cmake --build "$work/example" > "$work/build.log" 2>&1 || { cat "$work/build.log"; exit 1; }
bin="$work/prefix/bin"
region="-0.3:0.3,0.0:0.5,-0.3:0.3,-2.3:-1.7,-0.3:0.3,1.6:2.2,0.5:1.1"
(cd "$work" && env -u LAZYBOE_DATA_DIR "$bin/lazyboe-build" --out "$work/b.h5" --edges 600 \
  --region="$region" --theta 0.45 --env empty --quiet)   # a bundled scene, by name
"$bin/lazyboe-perturb" --bundle "$work/b.h5" --perturbations 2 --quiet
start=0,0.25,0,-2,0,1.9,0.8
goal=0.2,0.1,0.15,-1.85,-0.15,2.0,0.9
# The planning budget scales with LAZYBOE_TEST_TIME_SCALE (sanitizer builds are ~10x slower).
budget=$(awk -v s="${LAZYBOE_TEST_TIME_SCALE:-1}" 'BEGIN { print 5 * s }')
# "straight" is the example's own planner, registered at run time (register_planner).
for planner in lazyboe boe rrt straight; do
  out=$("$work/example/plan_one_query" "$work/b.h5" "$start" "$goal" "$planner" 0.3 "$budget")
  echo "$out"
  case "$out" in "$planner: solved in "*) ;; *) echo "FAIL: $planner did not solve"; exit 1 ;; esac
done
# Bad input: one line on stderr, non-zero exit.
if "$work/example/plan_one_query" "$work/b.h5" "$start" "9,9,9,9,9,9,9" 2> "$work/err"; then
  echo "FAIL: a goal outside the limits was accepted"; exit 1
fi
grep -q "goal.q: outside the joint limits" "$work/err" || { cat "$work/err"; exit 1; }
if "$work/example/plan_one_query" "$work/b.h5" "$start" "$goal" rrt 0.3 abc 2> "$work/err"; then
  echo "FAIL: a budget that is not a number was accepted"; exit 1
fi
grep -q "BUDGET: 'abc' is not a number" "$work/err" || { cat "$work/err"; exit 1; }
