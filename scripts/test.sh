#!/usr/bin/env bash
# The project's test command: installs missing dependencies (apt), configures, builds
# and runs every CTest test with --output-on-failure. Exits non-zero on any failure.
#
# Usage: scripts/test.sh [extra ctest arguments, e.g. -L geometry or -R Time]
# Environment: MRVS_BUILD_DIR (default build/), MRVS_JOBS (default nproc).
#
# When run as root, the tests run inside a private network namespace with only loopback
# up (unshare -n), so no test can send DDS (or any) traffic off this machine.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"

mrvs_build

step "tests"
ctest_cmd=(ctest --test-dir "$MRVS_BUILD" --output-on-failure -j "$MRVS_JOBS" --timeout 600 "$@")
if [[ $(id -u) -eq 0 ]] && command -v unshare >/dev/null && unshare -n true 2>/dev/null; then
  echo "(inside a private network namespace: loopback only)"
  unshare -n bash -c 'ip link set lo up && exec "$@"' _ "${ctest_cmd[@]}"
else
  echo "(not root or no unshare: tests run in the current network namespace)"
  "${ctest_cmd[@]}"
fi
