#!/usr/bin/env python3
"""Validates the bundled JSON data files (and example result lines) against the JSON Schemas in
schemas/."""
import json
import pathlib
import sys

import jsonschema

root = pathlib.Path(sys.argv[1])
cases = [("schemas/robot-config.schema.json", p) for p in sorted((root / "data/robots").glob("*.json"))]
cases += [("schemas/environment.schema.json", p) for p in sorted((root / "data/environments").glob("*.json"))]
for path in sorted((root / "data/queries").glob("*.jsonl")):
    schema = json.loads((root / "schemas/query.schema.json").read_text())
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if line.strip():
            cases.append(("schemas/query.schema.json", (path, n, json.loads(line))))
# Result lines as lazyboe-query writes them (post-processed, --raw and an error): the examples,
# and any result files named after ROOT (test_query_cli passes the tool's output).
results = sorted((root / "data/examples").glob("*results*.jsonl"))
results += [pathlib.Path(a).absolute() for a in sys.argv[2:]]
for path in results:
    for n, line in enumerate(path.read_text().splitlines(), 1):
        if line.strip():
            cases.append(("schemas/result.schema.json", (path, n, json.loads(line))))
passed = failed = 0
for schema_path, data_path in cases:
    schema = json.loads((root / schema_path).read_text())
    jsonschema.Draft202012Validator.check_schema(schema)
    if isinstance(data_path, tuple):
        data_path, line, doc = data_path
        name = f"{data_path}:{line}"
    else:
        doc = json.loads(data_path.read_text())
        name = str(data_path.relative_to(root))
    errors = list(jsonschema.Draft202012Validator(schema).iter_errors(doc))
    if errors:
        failed += 1
        for e in errors:
            print(f"{name}: {'/'.join(map(str, e.path))}: {e.message}")
    else:
        passed += 1
print(f"{passed} passed, {failed} failed")
sys.exit(1 if failed or not cases else 0)
