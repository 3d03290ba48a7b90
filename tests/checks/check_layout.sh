#!/usr/bin/env bash
# Fails if a folder of the fixed top-level layout or its README.md is missing.
set -euo pipefail
root=${1:?usage: check_layout.sh REPO_ROOT}
status=0
[[ -f "$root/CMakeLists.txt" ]] || { echo "missing top-level CMakeLists.txt"; status=1; }
for d in idl cloud_server edge_client common config scripts tests docker; do
  if [[ ! -d "$root/$d" ]]; then
    echo "missing folder $d/"; status=1
  elif [[ ! -s "$root/$d/README.md" ]]; then
    echo "missing or empty $d/README.md (one line on what lives there)"; status=1
  fi
done
[[ $status -eq 0 ]] && echo "layout ok"
exit $status
