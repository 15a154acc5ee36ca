#!/usr/bin/env bash
# check-format.sh SOURCE_DIR: every C and C++ file of the project is as clang-format (the
# root's .clang-format) writes it. Lists the files that are not, with the first differences.
set -euo pipefail
cd "$1"
if git rev-parse --is-inside-work-tree >/dev/null 2>&1; then
  mapfile -t files < <(git ls-files '*.c' '*.h' '*.cpp' '*.hpp')
else
  mapfile -t files < <(find common firmware host hil tests -name '*.c' -o -name '*.h' -o -name '*.cpp' -o -name '*.hpp')
fi
bad=0
for f in "${files[@]}"; do
  [ -f "$f" ] || continue  # deleted in the work tree, not yet in the index
  if ! clang-format --dry-run -Werror "$f" >/dev/null 2>&1; then
    echo "not formatted: $f (clang-format -i $f)"
    clang-format "$f" | diff "$f" - | head -10 || true
    bad=$((bad + 1))
  fi
done
echo "check-format: ${#files[@]} files, $bad not formatted"
[ "$bad" -eq 0 ]
