#!/usr/bin/env python3
"""Runs every shell command of README.md's code blocks and every Python block of README.md and
docs/python.md, on small data, so that the docs cannot drift from the tools (issue 30).

Usage: test_readme_commands.py SOURCE_DIR BUILD_DIR [DOC.md ...]

Each command runs in a fresh work folder in which `build`, `data`, `scripts` and `examples`
point at the build and source trees, so the README's paths work as written. A comment on the
line before a code fence adjusts the block for the test (rules separated by " | "):

    <!-- readme-test: skip (why) -->            the block is not run (e.g. `make test` itself)
    <!-- readme-test: OLD => NEW -->            text replaced in the block before it runs
    <!-- readme-test: TOOL += --opt V ... -->   options added to every TOOL command of the block
                                                that does not give them already
    <!-- readme-test: prelude CODE -->          Python run before the block (names it assumes)

In shell blocks an optional part `[...]` is kept when it is literal (`[--json]`) and dropped
when it holds a placeholder (an upper-case word such as DIR, or a `|` of choices). Python blocks
of one document run in order in one interpreter, as a reader would paste them. Exit status 0
when every command succeeded, 1 otherwise (each failure named by document and line).
"""

import json
import os
import re
import shlex
import shutil
import subprocess
import sys
import tempfile

MARKER = re.compile(r"<!--\s*readme-test:(.*?)-->")
PLACEHOLDER = re.compile(r"\b[A-Z][A-Z_]*\b|\|")


class Block:
    def __init__(self, doc, line, language, text, rules):
        self.doc, self.line, self.language, self.text, self.rules = doc, line, language, text, rules


def parse_rules(comment):
    return [r.strip() for r in comment.split(" | ") if r.strip()]


def extract_blocks(path):
    """The fenced code blocks of a Markdown file, with the rules of the marker before each."""
    blocks, lines = [], open(path, encoding="utf-8").read().split("\n")
    i = 0
    while i < len(lines):
        fence = re.match(r"^```(\w*)\s*$", lines[i])
        if not fence:
            i += 1
            continue
        rules = []
        marker = MARKER.search(lines[i - 1]) if i > 0 else None
        if marker:
            rules = parse_rules(marker.group(1))
        start, i = i + 1, i + 1
        while i < len(lines) and not lines[i].startswith("```"):
            i += 1
        blocks.append(Block(path, start, fence.group(1), "\n".join(lines[start:i]), rules))
        i += 1
    return blocks


def drop_placeholders(command):
    """Optional parts [...]: kept without brackets when literal, dropped with a placeholder."""
    out, depth, part = "", 0, ""
    for ch in command:
        if ch == "[":
            depth += 1
            if depth == 1:
                part = ""
                continue
        elif ch == "]" and depth > 0:
            depth -= 1
            if depth == 0:
                if not PLACEHOLDER.search(part):
                    out += part
                continue
        if depth > 0:
            part += ch
        else:
            out += ch
    return out


def add_options(command, tool, options):
    """Options `--name value ...` added to a command of `tool` that does not give them."""
    if not re.search(r"(^|/)" + re.escape(tool) + r"\b", command.split("#")[0]):
        return command
    words, added = shlex.split(options), []
    for k, word in enumerate(words):
        if not word.startswith("--"):
            continue
        value = [w for w in words[k + 1:k + 2] if not w.startswith("--")]
        if not re.search(r"(\s)" + re.escape(word) + r"(\s|=|$)", command):
            added += [word] + value
    code, sep, comment = command.partition(" #")
    return code.rstrip() + " " + " ".join(added) + (sep + comment if sep else "")


def apply_rules(block):
    text, prelude = block.text, ""
    for rule in block.rules:
        if rule.startswith("skip"):
            return None, ""
        if rule.startswith("prelude "):
            prelude += rule[len("prelude "):] + "\n"
        elif " => " in rule or rule.endswith(" =>"):
            old, new = (rule + " ").split(" => ", 1)
            new = new.strip()
            if old not in text:
                raise SystemExit(f"{block.doc}:{block.line}: readme-test rule '{rule}': "
                                 f"'{old}' is not in the block (the README changed?)")
            text = text.replace(old, new)
        elif " += " not in rule:
            raise SystemExit(f"{block.doc}:{block.line}: unknown readme-test rule '{rule}'")
    return text, prelude


def shell_commands(block, text):
    """The block's commands (continuation lines joined), each with its first line's number."""
    commands, pending, first = [], "", None
    for k, line in enumerate(text.split("\n")):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        if first is None:
            first = block.line + k + 1
        pending += line.rstrip()[:-1] + " " if line.rstrip().endswith("\\") else line
        if line.rstrip().endswith("\\"):
            continue
        command = drop_placeholders(pending)
        for rule in block.rules:
            if " += " in rule:
                tool, options = rule.split(" += ", 1)
                command = add_options(command, tool.strip(), options)
        commands.append((first, command))
        pending, first = "", None
    return commands


def make_work_dir(source, build):
    work = tempfile.mkdtemp(prefix="readme-test-")
    os.symlink(build, os.path.join(work, "build"))
    for name in ("data", "scripts", "examples"):
        os.symlink(os.path.join(source, name), os.path.join(work, name))
    write_inputs(work)
    return work


def write_inputs(work):
    """The files the README's commands read and the user is expected to have: logged states,
    configurations, a batch of queries, a trajectory, all for the Panda on the table."""
    ready = [0, -0.785, 0, -2.356, 0, 1.571, 0.785]
    home = [-0.2114, -0.0095, 0.1057, -2.2993, 0.0251, 1.806, 0.4022]
    n = len(ready)
    with open(os.path.join(work, "states.csv"), "w") as f:
        f.write(",".join([f"q{i}" for i in range(1, n + 1)] + [f"dq{i}" for i in range(1, n + 1)] +
                         [f"ddq{i}" for i in range(1, n + 1)]) + "\n")
        for q in (ready, home):
            f.write(",".join(str(v) for v in q + [0.1] * n + [0.0] * n) + "\n")
    with open(os.path.join(work, "configs.csv"), "w") as f:
        f.write(",".join(f"q{i}" for i in range(1, n + 1)) + "\n")
        for q in (ready, home):
            f.write(",".join(str(v) for v in q) + "\n")
    with open(os.path.join(work, "traj.csv"), "w") as f:  # the arm at rest for 0.1 s
        f.write(",".join(["t"] + [f"q{i}" for i in range(1, n + 1)] +
                         [f"dq{i}" for i in range(1, n + 1)]) + "\n")
        for k in range(101):
            f.write(",".join([f"{k / 1000:.3f}"] + [str(v) for v in home] + ["0"] * n) + "\n")
    demo = os.path.join(work, "data", "queries", "table-demo.jsonl")
    with open(demo) as f, open(os.path.join(work, "batch.jsonl"), "w") as out:
        for line in f.read().splitlines()[:5:2]:  # lazyboe, rrt and lazysp of the first problem
            out.write(line + "\n")


def run_shell(work, doc_name, line, command, failures):
    try:
        r = subprocess.run(["bash", "-c", command], cwd=work, capture_output=True, text=True,
                           stdin=subprocess.DEVNULL, timeout=300)
    except subprocess.TimeoutExpired:
        print(f"{doc_name}:{line}: FAILED (over 300 s): {command}", flush=True)
        failures.append(f"{doc_name}:{line}")
        return
    status = "ok" if r.returncode == 0 else f"FAILED (exit {r.returncode})"
    print(f"{doc_name}:{line}: {status}: {command}", flush=True)
    if r.returncode != 0:
        tail = (r.stderr or r.stdout).strip().splitlines()[-5:]
        print("    " + "\n    ".join(tail), flush=True)
        failures.append(f"{doc_name}:{line}")


DRIVER = r"""
import json, sys, traceback
blocks = json.load(open(sys.argv[1]))
scope = {"__name__": "__readme__"}
failed = 0
for b in blocks:
    try:
        exec(compile(b["prelude"], b["where"] + " (prelude)", "exec"), scope)
        exec(compile(b["code"], b["where"], "exec"), scope)
        print(b["where"] + ": ok", flush=True)
    except Exception:
        failed += 1
        print(b["where"] + ": FAILED\n" + traceback.format_exc(limit=3), flush=True)
sys.exit(1 if failed else 0)
"""


def run_python(work, doc_name, blocks, failures):
    spec = [{"where": f"{doc_name}:{b.line}", "code": code, "prelude": prelude}
            for b, code, prelude in blocks]
    spec_path = os.path.join(work, f"python-blocks-{os.path.basename(doc_name)}.json")
    with open(spec_path, "w") as f:
        json.dump(spec, f)
    env = dict(os.environ, PYTHONPATH=os.path.join(work, "build", "python"), MPLBACKEND="Agg")
    try:
        r = subprocess.run(["/usr/bin/python3", "-c", DRIVER, spec_path], cwd=work, env=env,
                           capture_output=True, text=True, timeout=400)
    except subprocess.TimeoutExpired:
        failures.append(f"{doc_name} (python blocks: over 400 s)")
        return
    print(r.stdout, end="", flush=True)
    if r.returncode != 0:
        print(r.stderr[-2000:], flush=True)
        failures += [line.split(": FAILED")[0] for line in r.stdout.splitlines()
                     if line.endswith(": FAILED")] or [doc_name + " (python)"]


def run_document(work, source, doc, failures):
    doc_name = os.path.relpath(doc, source) if doc.startswith(source) else doc
    python = []
    for block in extract_blocks(doc):
        if block.language not in ("sh", "python"):
            continue
        text, prelude = apply_rules(block)
        if text is None:
            print(f"{doc_name}:{block.line}: skipped ({'; '.join(block.rules)})", flush=True)
        elif block.language == "sh":
            for line, command in shell_commands(block, text):
                run_shell(work, doc_name, line, command, failures)
        else:
            python.append((block, text, prelude))
    if python:
        run_python(work, doc_name, python, failures)


def self_check(work):
    """The runner itself: a document with a broken command and a failing Python block must be
    reported as two failures, or a passing run above would prove nothing."""
    doc = os.path.join(work, "broken.md")
    with open(doc, "w") as f:
        f.write("```sh\nbuild/bin/lazyboe-robot info\n"
                "build/bin/lazyboe-robot info --no-such-option\n```\n\n"
                "```python\nimport lazyboe\nlazyboe.Robot().no_such_method()\n```\n")
    failures = []
    run_document(work, work, doc, failures)
    if failures != ["broken.md:3", "broken.md:6"]:
        sys.exit(f"self-check: the runner reported {failures} for a document with two broken "
                 "blocks (expected broken.md:3 and broken.md:6)")
    print("self-check: a broken command and a broken Python block are both reported")


def main():
    if len(sys.argv) < 3:
        sys.exit(__doc__.split("\n\n")[1])
    source, build = os.path.abspath(sys.argv[1]), os.path.abspath(sys.argv[2])
    docs = sys.argv[3:] or [os.path.join(source, "README.md"),
                            os.path.join(source, "docs", "python.md")]
    work = make_work_dir(source, build)
    print(f"work folder: {work}", flush=True)
    if len(sys.argv) == 3:
        self_check(work)
    failures = []
    for doc in docs:
        run_document(work, source, os.path.abspath(doc), failures)
    if failures:
        print(f"{len(failures)} documented command(s) failed: {', '.join(failures)}")
        sys.exit(1)
    shutil.rmtree(work)  # kept when something failed, to look into
    print("every documented command ran")


if __name__ == "__main__":
    main()
