#!/usr/bin/env bash
# The reference documentation of the public grading API (ros2course.kit), generated from its
# docstrings with pdoc into docs/api/ (or the folder given). Run after changing a kit step:
#   bash scripts/api_docs.sh            # -> docs/api/index.html
set -euo pipefail
cd "$(dirname "$0")/.."
OUT="${1:-docs/api}"
PY="${PYTHON:-.venv/bin/python}"
modules=(ros2course.kit)
for path in course/kit/*.py; do
  name="$(basename "$path" .py)"
  [ "$name" = "__init__" ] || modules+=("ros2course.kit.$name")
done
rm -rf "$OUT"
"$PY" -m pdoc "${modules[@]}" -o "$OUT" --docformat google --no-search --no-show-source
echo "API reference: $OUT/index.html"
