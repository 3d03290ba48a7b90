#!/usr/bin/env bash
# The shell and Python scripts parse, and every entry script answers --help with 0 and an
# unknown argument with 2 (before it builds or touches the network).
set -uo pipefail
root=$1
fail=0
for f in "$root"/scripts/*.sh "$root"/scripts/lib/*.sh "$root"/tests/checks/*.sh; do
  bash -n "$f" || { echo "syntax error: $f"; fail=1; }
done
for f in "$root"/scripts/*.py "$root"/scripts/lib/*.py; do
  [[ -e $f ]] || continue
  python3 -c 'import ast, sys; ast.parse(open(sys.argv[1]).read(), sys.argv[1])' "$f" || { echo "syntax error: $f"; fail=1; }
done
for s in demo.sh two_hosts.sh throttled_latency.sh run_experiments.sh containers.sh localisation_experiment.sh \
         registration_comparison.sh localise_replay.sh; do
  "$root/scripts/$s" --help >/dev/null 2>&1 || { echo "$s --help did not exit 0"; fail=1; }
  "$root/scripts/$s" --no-such-flag >/dev/null 2>&1
  [[ $? -eq 2 ]] || { echo "$s --no-such-flag did not exit 2"; fail=1; }
done
"$root/scripts/throttled_latency.sh" --burst 100 >/dev/null 2>&1
[[ $? -eq 2 ]] || { echo "throttled_latency.sh --burst 100 (below one frame) was not refused"; fail=1; }
"$root/scripts/throttled_latency.sh" --loss x >/dev/null 2>&1
[[ $? -eq 2 ]] || { echo "throttled_latency.sh --loss x was not refused"; fail=1; }
exit $fail
