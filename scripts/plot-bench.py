#!/usr/bin/python3
"""Draws the figures of a lazyboe-bench study from DIR/runs.csv, like the LazyBoE paper's:

  DIR/time_to_first_solution.png  box plot per planner, log scale, successful runs only
  DIR/final_cost.png              box plot per planner, successful runs only
  DIR/n_solutions.png             mean number of solutions per run (failures count 0), +- 1 SD
  DIR/success_rate.png            fraction of runs that found a solution

Planners appear in the order of their first row in runs.csv; LazyBoE is highlighted. Significance
marks are in DIR/summary.md, not on the figures.

usage: plot-bench.py DIR
Needs python3-matplotlib (Debian's, hence /usr/bin/python3); without it, prints one line and
exits 0. A missing or malformed runs.csv: one line naming the file and line, exit 1.
"""
import csv
import math
import os
import statistics
import sys

COLUMNS = ["planner", "problem", "repeat", "seed", "success", "time_to_first_solution",
           "best_cost", "n_solutions", "nodes", "simulations", "lazy_edges", "collision_checks",
           "budget", "failure"]
HIGHLIGHT, BASELINE = "#d62728", "#7f7f7f"


class BadInput(Exception):
    pass


def read_runs(path):
    """Rows of runs.csv as dicts with typed fields; BadInput names the file and line."""
    try:
        f = open(path, newline="", encoding="utf-8")
    except OSError as e:
        raise BadInput(f"{path}: cannot read: {e.strerror}")
    with f:
        reader = csv.reader(f)
        runs = []
        try:
            header = next(reader, None)
            if header is None:
                raise BadInput(f"{path}:1: empty file, expected the runs.csv header")
            missing = [c for c in COLUMNS if c not in header]
            if missing:
                raise BadInput(f"{path}:1: header lacks column(s) {', '.join(missing)}")
            col = {name: header.index(name) for name in COLUMNS}
            for fields in reader:
                line = reader.line_num
                if not fields:
                    continue
                if len(fields) != len(header):
                    raise BadInput(f"{path}:{line}: {len(fields)} fields, the header has "
                                   f"{len(header)}")
                runs.append(parse_row(path, line, {n: fields[i] for n, i in col.items()}))
        except csv.Error as e:
            raise BadInput(f"{path}:{reader.line_num}: {e}")
        except UnicodeDecodeError:
            raise BadInput(f"{path}:{reader.line_num + 1}: not UTF-8 text")
    if not runs:
        raise BadInput(f"{path}:1: no runs after the header")
    return runs


def parse_row(path, line, row):
    def number(name, optional=False, integer=False):
        text = row[name].strip()
        if text == "" and optional:
            return None
        try:
            value = int(text) if integer else float(text)
        except ValueError:
            raise BadInput(f"{path}:{line}: {name} is '{text}', expected "
                           f"{'an integer' if integer else 'a number'}")
        if not math.isfinite(value) or value < 0:
            raise BadInput(f"{path}:{line}: {name} is '{text}', expected a finite value >= 0")
        return value

    if not row["planner"].strip():
        raise BadInput(f"{path}:{line}: empty planner")
    if row["success"].strip() not in ("0", "1"):
        raise BadInput(f"{path}:{line}: success is '{row['success']}', expected 0 or 1")
    run = {"planner": row["planner"].strip(), "success": row["success"].strip() == "1",
           "time": number("time_to_first_solution", optional=True),
           "cost": number("best_cost", optional=True),
           "n_solutions": number("n_solutions", integer=True),
           "budget": number("budget")}
    if run["success"] and (run["time"] is None or run["cost"] is None):
        raise BadInput(f"{path}:{line}: a successful run needs time_to_first_solution and "
                       "best_cost")
    return run


def by_planner(runs):
    order, groups = [], {}
    for r in runs:
        if r["planner"] not in groups:
            order.append(r["planner"])
            groups[r["planner"]] = []
        groups[r["planner"]].append(r)
    return order, groups


def is_lazyboe(name):
    return name.lower() == "lazyboe"


def style_axes(ax, planners, labels):
    ax.set_xticks(range(1, len(planners) + 1))
    ax.set_xticklabels(labels)
    for tick, name in zip(ax.get_xticklabels(), planners):
        if is_lazyboe(name):
            tick.set_fontweight("bold")
            tick.set_color(HIGHLIGHT)
    ax.grid(axis="y", alpha=0.3)


def box_plot(plt, planners, groups, key, path, title, ylabel, log):
    fig, ax = plt.subplots(figsize=(max(4.0, 1.3 * len(planners) + 1.5), 4.2))
    data = [[r[key] for r in groups[p] if r["success"]] for p in planners]
    if log:  # a time of 0 cannot be drawn on a log axis
        data = [[max(v, 1e-6) for v in d] for d in data]
    boxes = ax.boxplot(data, patch_artist=True, widths=0.6, medianprops={"color": "black"})
    for box, name in zip(boxes["boxes"], planners):
        box.set_facecolor(HIGHLIGHT if is_lazyboe(name) else BASELINE)
        box.set_alpha(0.75)
    for i, d in enumerate(data, 1):
        if not d:
            ax.text(i, 0.5, "no solution", transform=ax.get_xaxis_transform(), ha="center",
                    va="center", rotation=90, color=BASELINE)
    if log:
        ax.set_yscale("log")
    style_axes(ax, planners, [f"{p}\nn={len(d)}" for p, d in zip(planners, data)])
    ax.set_title(title, fontsize=10)
    ax.set_ylabel(ylabel)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def bar_plot(plt, planners, values, errors, path, title, ylabel, ylim, labels, value_text):
    fig, ax = plt.subplots(figsize=(max(4.0, 1.3 * len(planners) + 1.5), 4.2))
    x = range(1, len(planners) + 1)
    colors = [HIGHLIGHT if is_lazyboe(p) else BASELINE for p in planners]
    ax.bar(x, values, yerr=errors, color=colors, alpha=0.75, width=0.6, capsize=4 if errors else 0)
    for i, v, e in zip(x, values, errors or [0.0] * len(values)):
        ax.text(i, v + e, value_text(v), ha="center", va="bottom", fontsize=8)
    if ylim:
        ax.set_ylim(*ylim)
    style_axes(ax, planners, labels)
    ax.set_title(title, fontsize=10)
    ax.set_ylabel(ylabel)
    fig.tight_layout()
    fig.savefig(path, dpi=120)
    plt.close(fig)


def main(argv):
    if len(argv) != 2 or argv[1].startswith("-"):
        print("usage: plot-bench.py DIR", file=sys.stderr)
        return 2
    directory = argv[1]
    try:
        runs = read_runs(os.path.join(directory, "runs.csv"))
    except BadInput as e:
        print(f"plot-bench: {e}", file=sys.stderr)
        return 1
    try:
        import matplotlib
        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        print("plot-bench: python3-matplotlib is not installed; figures skipped", file=sys.stderr)
        return 0

    planners, groups = by_planner(runs)
    budgets = sorted({r["budget"] for r in runs})
    budget = f"{budgets[0]:g} s" if len(budgets) == 1 else f"{budgets[0]:g}-{budgets[-1]:g} s"
    box_plot(plt, planners, groups, "time", os.path.join(directory, "time_to_first_solution.png"),
             f"Time to first solution (successful runs only; failed runs are excluded,\n"
             f"see success_rate.png; budget {budget})", "time to first solution (s, log scale)",
             log=True)
    box_plot(plt, planners, groups, "cost", os.path.join(directory, "final_cost.png"),
             "Final solution cost (best path's joint-space arc length; successful runs only)",
             "final cost (rad)", log=False)

    counts = [[r["n_solutions"] for r in groups[p]] for p in planners]
    means = [statistics.fmean(c) for c in counts]
    sds = [statistics.stdev(c) if len(c) > 1 else 0.0 for c in counts]
    bar_plot(plt, planners, means, sds, os.path.join(directory, "n_solutions.png"),
             "Number of solutions per run (mean ± 1 standard deviation; a failed run counts 0)",
             "solutions per run", None, [f"{p}\nn={len(c)}" for p, c in zip(planners, counts)],
             lambda v: f"{v:.2f}")

    runs_of = [groups[p] for p in planners]
    rates = [sum(r["success"] for r in g) / len(g) for g in runs_of]
    bar_plot(plt, planners, rates, None, os.path.join(directory, "success_rate.png"),
             f"Success rate (runs that found a solution within the budget, {budget})",
             "success rate", (0, 1.08),
             [f"{p}\n{sum(r['success'] for r in g)}/{len(g)}" for p, g in zip(planners, runs_of)],
             lambda v: f"{100 * v:.0f}%")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
