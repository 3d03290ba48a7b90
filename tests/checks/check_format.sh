#!/usr/bin/env bash
# Fails if a project C++ file (tracked or not ignored by git) is not clang-formatted.
# Fix: clang-format -i <file>   (style in .clang-format)
set -euo pipefail
clang_format=${1:?usage: check_format.sh CLANG_FORMAT REPO_ROOT}
root=${2:?usage: check_format.sh CLANG_FORMAT REPO_ROOT}
cd "$root"
mapfile -t files < <(git ls-files --cached --others --exclude-standard -- '*.h' '*.hpp' '*.cpp' '*.cc' 2>/dev/null)
[[ ${#files[@]} -gt 0 ]] || { echo "no files (not a git checkout?)"; exit 0; }
bad=()
for f in "${files[@]}"; do
  [[ -f "$f" ]] || continue
  "$clang_format" --dry-run -Werror --style=file "$f" >/dev/null 2>&1 || bad+=("$f")
done
if [[ ${#bad[@]} -gt 0 ]]; then
  echo "not formatted (run: clang-format -i ${bad[*]}):"
  printf '  %s\n' "${bad[@]}"
  exit 1
fi
echo "${#files[@]} files formatted"
