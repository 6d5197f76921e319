#!/usr/bin/env python3
"""`make demo` reads like a tour (issue 30): scripts/demo.sh, run on the build tree into a folder
of its own, succeeds; each of its sections says in a line what to look at and fits one screen
(progress lines aside, which a terminal shows as one line); it ends with the viewer page's path.
The same for `make demo-ur5` (issue 28: the UR5 from its URDF to a viewer page), whose lazysp
must solve every query of its batch.

Usage: test_demo_tour.py SOURCE_DIR BUILD_DIR [SCRIPT SECTIONS]   (default: demo.sh 6)
"""

import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

SCREEN_LINES = 50
PROGRESS = re.compile(r"^(lazyboe-\w+|workspace index): \d+/\d+ \(")


def main():
    source, build = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    script, expected_sections = (sys.argv[3], int(sys.argv[4])) if len(sys.argv) > 4 else \
        ("demo.sh", 6)
    out = tempfile.mkdtemp(prefix="demo-tour-")
    r = subprocess.run(["bash", os.path.join(source, "scripts", script), build, out],
                       cwd=source, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True,
                       timeout=900)  # one stream, in the order a terminal shows it
    if r.returncode != 0:
        sys.exit(f"{script} failed (exit {r.returncode}):\n{r.stdout[-3000:]}")
    sections, titles, current = {}, [], None
    for line in r.stdout.splitlines():
        if line.startswith("== "):
            current = line
            titles.append(line)
            sections[current] = []
        elif current and not PROGRESS.match(line):
            sections[current].append(line)
    problems = []
    if len(titles) != expected_sections:
        problems.append(f"expected {expected_sections} sections, found {len(titles)}: {titles}")
    for title in titles:
        body = sections[title]
        if len(body) + 1 > SCREEN_LINES:
            problems.append(f"'{title}': {len(body) + 1} lines, more than a screen ({SCREEN_LINES})")
        if not body or not body[0].startswith("   ("):
            problems.append(f"'{title}': no line under the title saying what it shows")
    last = r.stdout.strip().splitlines()[-1]
    page = os.path.join(os.path.realpath(out), "view.html")
    if not re.match(r"demo(-\w+)?: done", last) or page not in last:
        problems.append(f"the last line does not give the viewer page ({page}): {last}")
    if not os.path.isfile(page):
        problems.append(f"no viewer page at {page}")
    results = os.path.join(out, "results.jsonl")
    lazysp = [json.loads(l) for l in open(results)] if os.path.isfile(results) else []
    lazysp = [q for q in lazysp if q.get("planner") == "lazysp"]
    if script != "demo.sh" and (not lazysp or not all(q.get("success") for q in lazysp)):
        problems.append(f"lazysp solved {sum(bool(q.get('success')) for q in lazysp)} of "
                        f"{len(lazysp)} queries of the demo batch (expected all)")
    if problems:
        sys.exit("\n".join(problems))
    shutil.rmtree(out)
    print(f"{script}: {len(titles)} sections, the longest {max(len(sections[t]) + 1 for t in titles)} "
          "lines; each says what to look at; the viewer page's path at the end")


if __name__ == "__main__":
    main()
