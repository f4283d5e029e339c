#!/usr/bin/env bash
# The tree stays in the house format (.clang-format, Debian 12's clang-format 14): every C++
# file git tracks is formatted as clang-format would. Fails naming the files that are not, with
# the command that fixes them.
# Usage: format_check.sh SOURCE_DIR CLANG_FORMAT
set -euo pipefail
cd "$1"
clang_format=$2
mapfile -t files < <(git ls-files '*.cpp' '*.h')
[ ${#files[@]} -gt 0 ] || { echo "format_check: no C++ files found under $1 (not a git checkout?)" >&2; exit 1; }
bad=()
for f in "${files[@]}"; do
  if ! "$clang_format" --dry-run -Werror "$f" >/dev/null 2>&1; then bad+=("$f"); fi
done
if [ ${#bad[@]} -gt 0 ]; then
  echo "format_check: ${#bad[@]} of ${#files[@]} files are not in the house format:" >&2
  printf '  %s\n' "${bad[@]}" >&2
  echo "fix with: $clang_format -i ${bad[*]}" >&2
  exit 1
fi
echo "format_check: ${#files[@]} files in the house format"
