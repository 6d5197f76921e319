#!/usr/bin/python3
"""scripts/plot-bench.py on the synthetic fixture tests/data/bench-runs.csv: the four figures,
its one-line errors, and its message without matplotlib. Exits 77 (skipped) without matplotlib.

usage: test_plot_bench.py SOURCE_DIR
"""
import os
import pathlib
import shutil
import subprocess
import sys
import tempfile

FIGURES = ["time_to_first_solution.png", "final_cost.png", "n_solutions.png", "success_rate.png"]

root = pathlib.Path(sys.argv[1])
script = root / "scripts/plot-bench.py"
fixture = root / "tests/data/bench-runs.csv"
try:
    import matplotlib  # noqa: F401
except ImportError:
    print("SKIP: python3-matplotlib is not installed")
    sys.exit(77)

failures = []


def check(condition, what):
    print(("ok   " if condition else "FAIL ") + what)
    if not condition:
        failures.append(what)


def run(directory, env=None):
    return subprocess.run([sys.executable, str(script), str(directory)], capture_output=True,
                          text=True, env=env, timeout=300)


with tempfile.TemporaryDirectory() as tmp:
    tmp = pathlib.Path(tmp)

    good = tmp / "good"
    good.mkdir()
    shutil.copy(fixture, good / "runs.csv")
    r = run(good)
    check(r.returncode == 0, f"fixture: exit 0 (got {r.returncode}: {r.stderr.strip()})")
    for name in FIGURES:
        path = good / name
        ok = path.is_file() and path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
        check(ok and path.stat().st_size > 1000, f"fixture: {name} is a PNG")

    bad = tmp / "bad"
    bad.mkdir()
    lines = fixture.read_text().splitlines()
    lines[2] = lines[2].replace(",synthetic-2,0,2,1,", ",synthetic-2,0,2,yes,")
    (bad / "runs.csv").write_text("\n".join(lines) + "\n")
    r = run(bad)
    check(r.returncode == 1, f"bad row: exit 1 (got {r.returncode})")
    check(r.stderr.count("\n") == 1 and f"{bad / 'runs.csv'}:3: success" in r.stderr,
          f"bad row: one line naming file and line (got {r.stderr!r})")
    check(not any((bad / n).exists() for n in FIGURES), "bad row: no figures")

    r = run(tmp / "missing")
    check(r.returncode == 1, f"missing runs.csv: exit 1 (got {r.returncode})")
    check(r.stderr.count("\n") == 1 and str(tmp / "missing" / "runs.csv") in r.stderr,
          f"missing runs.csv: one line naming the file (got {r.stderr!r})")

    # A matplotlib that fails to import stands in for a machine without it.
    fake = tmp / "no-matplotlib"
    (fake / "matplotlib").mkdir(parents=True)
    (fake / "matplotlib/__init__.py").write_text("raise ImportError('not installed')\n")
    plain = tmp / "plain"
    plain.mkdir()
    shutil.copy(fixture, plain / "runs.csv")
    r = run(plain, env=dict(os.environ, PYTHONPATH=str(fake)))
    check(r.returncode == 0, f"no matplotlib: exit 0 (got {r.returncode})")
    check(r.stdout + r.stderr ==
          "plot-bench: python3-matplotlib is not installed; figures skipped\n",
          f"no matplotlib: the one-line message (got {r.stdout + r.stderr!r})")
    check(not any((plain / n).exists() for n in FIGURES), "no matplotlib: no figures")

sys.exit(1 if failures else 0)
