#!/usr/bin/env bash
# Benchmark: wall time of generating a 30 s indoor sequence (V1_01_easy, preset easy, seed 1)
# with dataset_simulator, repeated N times; prints every run and the median.
# Target (issue 3): median <= 60 s on a 2-core machine.
#
# Usage: scripts/bench_simulator.sh [RUNS] [extra dataset_simulator flags...]   (default 3 runs)
# Environment: MRVS_SHARED_DIR (default tests/, which holds data/euroc_groundtruth/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"

runs=${1:-3}
shift || true
traj=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}/data/euroc_groundtruth/V1_01_easy.txt
[[ -f $traj ]] || { echo "bench_simulator.sh: missing $traj" >&2; exit 1; }

mrvs_build --target dataset_simulator >/dev/null
work=$(mktemp -d)
trap 'rm -rf "$work"' EXIT

step "generating a 30 s indoor sequence $runs times ($(nproc) cores)"
times=()
for i in $(seq "$runs"); do
  start=$(date +%s%N)
  "$MRVS_BUILD/bin/dataset_simulator" --trajectory "$traj" --profile indoor --duration 30 --seed 1 \
      --out "$work/seq" --overwrite --log-level warn "$@" >"$work/report.txt"
  t=$(awk -v a="$start" -v b="$(date +%s%N)" 'BEGIN { printf "%.3f", (b - a) / 1e9 }')
  times+=("$t")
  printf 'run %d: %.1f s  (%s)\n' "$i" "$t" "$(grep -E 'FRAMES|SECONDS_RENDER|SECONDS_MAP' "$work/report.txt" | tr '\n' ' ')"
done
du -sh "$work/seq" | awk '{print "dataset size: " $1}'
median=$(printf '%s\n' "${times[@]}" | sort -n | awk '{a[NR]=$1} END {print (NR % 2) ? a[(NR+1)/2] : (a[NR/2]+a[NR/2+1])/2}')
printf 'MEDIAN_SECONDS_30S_INDOOR: %.1f\n' "$median"
