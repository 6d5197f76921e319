#!/bin/bash
# Fails if a sanitizer wrote a report under DIR (make test-sanitize, make test-tsan). Catches
# reports from tools that a test expected to fail anyway, whose exit status hides the report.
set -euo pipefail
dir=$1
shopt -s nullglob
logs=("$dir"/*)
if ((${#logs[@]})); then
  for f in "${logs[@]}"; do
    echo "=== $f"
    cat "$f"
  done
  echo "sanitizer reports: ${#logs[@]} file(s) under $dir" >&2
  exit 1
fi
echo "sanitizer reports: none"
