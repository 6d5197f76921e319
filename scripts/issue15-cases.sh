#!/bin/bash
# Reruns the cases that issue 15 listed (its first section) against the tools in BIN_DIR and
# prints one Markdown table row per command: case, command, exit status, the first line of
# stderr (or of stdout where the answer is there). docs/reliability.md, "Rerun of issue 15's
# cases", records its output. Usage: scripts/issue15-cases.sh BIN_DIR [WORK_DIR]
# The commands run inside WORK_DIR (default: a fresh temporary directory), so the table's paths
# are relative. Needs a C compiler and HDF5's headers (for the helper that damages a bundle).
set -uo pipefail
bin=$(cd "$1" && pwd)
src=$(cd "$(dirname "$0")/.." && pwd)
work=${2:-$(mktemp -d)}
mkdir -p "$work" && cd "$work" || exit 1
export PATH="$bin:$PATH"

# ---- helpers --------------------------------------------------------------------------------

# row CASE CMD...: runs CMD (a shell string) and prints the row. STREAM=out takes stdout.
row() {
  local name=$1 cmd=$2
  bash -c "$cmd" >out.txt 2>err.txt
  local rc=$?
  local text
  # The error line where there is one (a tool's progress lines come before it), else the first.
  if [[ ${STREAM:-err} == out ]]; then
    text=$(head -c 400 out.txt | head -n 1)
  else
    text=$(grep -m 1 'error' err.txt || head -n 1 err.txt)
  fi
  local lines
  lines=$(wc -l <err.txt)
  # More lines: the last one too (what a command lists after the tool ran).
  if [[ ${STREAM:-err} == err && $lines -gt 1 && $(tail -n 1 err.txt) != "$text" ]]; then
    text="$text ... $(tail -n 1 err.txt)"
  fi
  text=${text/%left: /left: nothing}
  text=${text//|/\\|}
  printf '| %s | `%s` | %s | %s |\n' "$name" "$cmd" "$rc" "$text"
}

# A copy of the bundled Panda in DIR with the first FROM in FILE replaced by TO.
panda_with() {
  local dir=$1 file=$2 from=$3 to=$4
  rm -rf "$dir" && mkdir -p "$dir"
  cp "$src/data/robots/panda.json" "$src/data/robots/panda.urdf" "$dir/"
  FROM=$from TO=$to python3 - "$dir/$file" <<'EOF'
import os, sys
p = sys.argv[1]
s = open(p).read()
i = s.find(os.environ["FROM"])
assert i >= 0, os.environ["FROM"]
open(p, "w").write(s[:i] + os.environ["TO"] + s[i + len(os.environ["FROM"]):])
EOF
}

# poke FILE DATASET INDEX double|u64 VALUE: overwrites one element of a contiguous dataset in
# place, as a damaged or hand-edited file would have it (the helper asks HDF5 for its offset).
poke_tool=$work/.poke
if [[ ! -x $poke_tool ]]; then
  cat >"$work/.poke.c" <<'EOF'
#include <hdf5.h>
#include <stdio.h>
#include <stdlib.h>
#include <string.h>
int main(int argc, char** argv) {
  if (argc != 6) return 2;
  hid_t f = H5Fopen(argv[1], H5F_ACC_RDONLY, H5P_DEFAULT);
  hid_t d = H5Dopen2(f, argv[2], H5P_DEFAULT);
  haddr_t off = H5Dget_offset(d);
  H5Dclose(d);
  H5Fclose(f);
  if (off == HADDR_UNDEF) return 3;
  unsigned long long i = strtoull(argv[3], 0, 10);
  FILE* out = fopen(argv[1], "r+b");
  fseek(out, (long)(off + i * 8), SEEK_SET);
  if (!strcmp(argv[4], "double")) {
    double v = strtod(argv[5], 0);
    fwrite(&v, 8, 1, out);
  } else {
    unsigned long long v = strtoull(argv[5], 0, 10);
    fwrite(&v, 8, 1, out);
  }
  return fclose(out) != 0;
}
EOF
  cc -O1 -I/usr/include/hdf5/serial "$work/.poke.c" -o "$poke_tool" -L/usr/lib/x86_64-linux-gnu/hdf5/serial -lhdf5 || exit 1
fi

# ---- inputs ---------------------------------------------------------------------------------

lazyboe-build --edges 300 --out b.h5 --quiet || exit 1
lazyboe-perturb --bundle b.h5 --perturbations 4 --quiet || exit 1
printf '%s\n' '{"id": "a", "planner": "boe", "start": [0, 0, 0, -1.5, 0, 1.5, 0], "goal": {"q": [0.3, 0, 0, -1.5, 0, 1.5, 0]}, "stop_at_first": true}' >q.jsonl
echo 'q1,q2,q3,q4,q5,q6,q7,dq1,dq2,dq3,dq4,dq5,dq6,dq7,ddq1,ddq2,ddq3,ddq4,ddq5,ddq6,ddq7' >x.csv
echo '0,0,0,-1.5,0,1.5,0,0,0,0,0,0,0,0,0,0,0,0,0,0,0' >>x.csv
printf 'q1,q2,q3,q4,q5,q6,q7\n0,0,0,-1.5,0,1.5,0\n' >c.csv
printf 'q1,q2,q3,q4,q5,q6,q7\n0x10,0,0,-1.5,0,1.5,0\n' >hex.csv
ln -sf b.h5 link.h5
mkdir -p adir
cp "$src/data/environments/table.json" table.json
python3 - <<'EOF'
s = open("table.json").read()
open("big-box.json", "w").write(s.replace("[0.6, 1.2, 0.04]", "[1e308, 1.2, 0.04]", 1))
i = s.find('"size"')
open("dup-key.json", "w").write(s[:i] + '"size": [1, 1, 1], ' + s[i:])
EOF
printf '%s\n' '{"id": "a", "planner": "boe", "budget": 9.3e9, "start": [0, 0, 0, -1.5, 0, 1.5, 0], "goal": {"q": [0.3, 0, 0, -1.5, 0, 1.5, 0]}}' >budget.jsonl
printf '%s\n' '{"id": "b", "planner": "boe", "budget": 1, "budget": 2, "start": [0, 0, 0, -1.5, 0, 1.5, 0], "goal": {"q": [0.3, 0, 0, -1.5, 0, 1.5, 0]}}' >dup.jsonl
for d in q0-nan:/edges/q0:17:double:nan q0-big:/edges/q0:3:double:1e308 plazy-nan:/perturbation/p_lazy_prop:5:double:nan offset:/edges/sample_offset:300:u64:1073741824; do
  IFS=: read -r name ds idx type val <<<"$d"
  cp b.h5 "dmg-$name.h5" && "$poke_tool" "dmg-$name.h5" "$ds" "$idx" "$type" "$val" || exit 1
done
panda_with mass-abc panda.urdf '<mass value="0.629769"/>' '<mass value="abc"/>'
panda_with mass-prefix panda.urdf '<mass value="0.629769"/>' '<mass value="4.97abc"/>'
panda_with ixx panda.urdf 'ixx="' 'ixx="0.7x" ixx_was="'
panda_with mass-huge panda.urdf '<mass value="0.629769"/>' '<mass value="1e308"/>'
panda_with effort-nan panda.urdf 'effort="' 'effort="nan" was="'
panda_with no-limit panda.urdf '<limit ' '<limits '
panda_with joint-type panda.urdf '<joint name="panda_joint1" type="revolute">' '<joint name="panda_joint1" type="spherical">'
panda_with origin panda.urdf '<origin xyz="-0.041018 -0.00014 0.049974"' '<origin xyz="-0.041018 -0.00014"'
panda_with overflow panda.json '"control_rate": ' '"control_rate": 1e400, "x": '
panda_with urdf-dir panda.json '"urdf": "panda.urdf"' '"urdf": "../adir"'
rm -rf robot moved && mkdir robot && cp "$src/data/robots/panda.json" "$src/data/robots/panda.urdf" robot/
lazyboe-build --edges 5 --robot robot/panda.json --out moved.h5 --quiet && mv robot moved
python3 - <<'EOF'
import random
random.seed(1)
with open("big.csv", "w") as f:
    f.write("q1,q2,q3,q4,q5,q6,q7\n")
    for k in range(100000):
        f.write("%.4f,0.1,0,-1.5,0,1.5,%.4f\n" % (-1 + 2 * (k % 1000) / 1000, 0.001 * (k % 97)))
EOF

# ---- the cases ------------------------------------------------------------------------------

echo '| case | command | exit | message |'
echo '|---|---|---|---|'
rm -rf fs && mkdir fs
row "full disk: build (file-size limit 100 KiB)" 'ulimit -f 100; lazyboe-build --edges 300 --out fs/out.h5 --quiet; s=$?; echo "left: $(ls fs)" >&2; exit $s'
lazyboe-build --edges 300 --out fs/p.h5 --quiet
lim=$(($(stat -c %s fs/p.h5) / 1024 + 1)) # the analysis does not fit
cp fs/p.h5 p-before.h5
row "full disk: perturb (limit = bundle + 1 KiB)" "ulimit -f $lim; lazyboe-perturb --bundle fs/p.h5 --perturbations 2 --quiet; s=\$?; cmp -s p-before.h5 fs/p.h5 && echo \"bundle unchanged; left: \$(ls fs)\" >&2; exit \$s"
if mkdir -p tmpfs && mount -t tmpfs -o size=2m tmpfs tmpfs 2>/dev/null; then
  row "full disk: build on a 2 MB tmpfs" 'lazyboe-build --edges 3000 --out tmpfs/out.h5 --quiet; s=$?; echo "left: $(ls tmpfs)" >&2; exit $s'
  umount tmpfs
else
  echo "| full disk: build on a 2 MB tmpfs | (mount -t tmpfs refused here: no privilege) | - | not run |"
fi
row "output = bundle" 'lazyboe-query --bundle b.h5 --queries q.jsonl --out b.h5'
row "output = bundle through a symlink" 'lazyboe-query --bundle b.h5 --queries q.jsonl --out link.h5'
row "output = queries" 'lazyboe-query --bundle b.h5 --queries q.jsonl --out q.jsonl'
row "output = input, torques" 'lazyboe-robot torques --in x.csv --out x.csv'
row "output = input, check" 'lazyboe-robot check --in c.csv --out ./c.csv'
row "URDF mass \"abc\"" 'lazyboe-robot info --robot mass-abc/panda.json'
row "URDF mass \"4.97abc\"" 'lazyboe-robot info --robot mass-prefix/panda.json'
row "URDF ixx \"0.7x\"" 'lazyboe-robot info --robot ixx/panda.json'
row "URDF mass 1e308" 'lazyboe-robot info --robot mass-huge/panda.json'
STREAM=out row "query budget 9.3e9 s (the result line)" 'lazyboe-query --bundle b.h5 --queries budget.jsonl --quiet'
row "bench --budget nan" 'lazyboe-bench --bundle b.h5 --out study --budget nan --problems 1 --planners boe'
row "environment box size 1e308" 'lazyboe-robot check --env big-box.json --in c.csv --out r.csv'
row "--queries a directory" 'lazyboe-query --bundle b.h5 --queries adir --out r.jsonl'
for d in q0-nan q0-big plazy-nan offset; do
  row "bundle damage $d: inspect" "lazyboe-build --inspect dmg-$d.h5"
  row "bundle damage $d: query" "lazyboe-query --bundle dmg-$d.h5 --queries q.jsonl --quiet"
  row "bundle damage $d: bench" "lazyboe-bench --bundle dmg-$d.h5 --out study-$d --problems 1 --budget 0.1 --planners boe --quiet --no-figures"
done
row "duplicate key, environment" 'lazyboe-robot check --env dup-key.json --in c.csv --out r.csv'
STREAM=out row "duplicate key, query line" 'lazyboe-query --bundle b.h5 --queries dup.jsonl --quiet'
row "0x10 in a CSV" 'lazyboe-robot check --in hex.csv --out r.csv'
row "directory as robot config" 'lazyboe-robot info --robot adir'
row "directory as URDF" 'lazyboe-robot info --robot urdf-dir/panda.json'
row "directory as environment" 'lazyboe-robot check --env adir --in c.csv --out r.csv'
row "directory as CSV" 'lazyboe-robot check --in adir --out r.csv'
row "URDF effort nan" 'lazyboe-robot info --robot effort-nan/panda.json'
row "URDF missing <limit>" 'lazyboe-robot info --robot no-limit/panda.json'
row "URDF unsupported joint type" 'lazyboe-robot info --robot joint-type/panda.json'
row "URDF bad origin" 'lazyboe-robot info --robot origin/panda.json'
row "robot config number overflow" 'lazyboe-robot info --robot overflow/panda.json'
row "unwritable build output" 'lazyboe-build --edges 5 --out missing-dir/b.h5 --quiet'
row "moved robot config" 'lazyboe-query --bundle moved.h5 --queries q.jsonl'
row "same build twice: bytes that differ" 'lazyboe-build --edges 50 --out same1.h5 --quiet && lazyboe-build --edges 50 --out same2.h5 --quiet; echo "$(cmp -l same1.h5 same2.h5 | wc -l) bytes differ" >&2; exit 0'
STREAM=out row "option after the subcommand" 'lazyboe-robot info --json --robot '"$src"'/data/robots/panda.json | grep -m 1 -E "^  .name.: .panda."'
row "check stopped by SIGTERM" 'lazyboe-robot check --in big.csv --out big-r.csv & pid=$!; sleep 1.5; kill -TERM $pid; wait $pid; s=$?; echo "left: $(ls big-r* 2>/dev/null)" >&2; exit $s'
