#!/usr/bin/env bash
# Tuning the localisation on dumped requests (issue 30): localises every request dumped by
# `scripts/registration_comparison.sh --dumps-only` (or localise_probe --dump) again with the
# shipped config/map_indoor.yaml plus any `--map-set` overrides, without VIO, and summarises
# (scripts/lib/replay_summary.py): the cloud's ok / wrong / ambiguous answers, its registration
# time on one core, and what the edge's acceptance rule would make of them per clip (simulated,
# with and without estimator.localisation.guesses_confirm). Writes OUT/replay.txt (per request,
# localise_probe's REPLAY lines) and OUT/summary.txt.
#
# Usage: scripts/localise_replay.sh --from DIR [--seed N] [--out DIR] [--map-set KEY=VALUE ...]
#   --from  the --out folder of registration_comparison.sh: DIR/dumps/<trajectory>/start<S>/
#           and the maps DIR/data/<trajectory>_seed<N>.mrvm
#   defaults: seed 1, OUT build/localise_replay
# Example (the tuning set: seed 1, offset 0, 10 clips per trajectory):
#   scripts/registration_comparison.sh --dumps-only --seed 1 --per-trajectory 10 --offset 0 --out /tmp/s1
#   scripts/localise_replay.sh --from /tmp/s1 --map-set localise.yaw_step_deg=2
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"

from=""
seed=1
out=$MRVS_BUILD/localise_replay
sets=()
while [[ $# -gt 0 ]]; do
  case $1 in
    --from) from=${2:?}; shift 2 ;;
    --seed) seed=${2:?}; shift 2 ;;
    --out) out=${2:?}; shift 2 ;;
    --map-set) sets+=(--map-set "${2:?}"); shift 2 ;;
    -h|--help) sed -n '2,16p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "localise_replay.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ -n $from && -d $from/dumps ]] || { echo "localise_replay.sh: give --from DIR with DIR/dumps (registration_comparison.sh --dumps-only --out DIR)" >&2; exit 2; }
mrvs_build --target localise_probe
mkdir -p "$out"
export OMP_NUM_THREADS=1
: >"$out/replay.txt"
for clip in "$from"/dumps/*/start*/; do
  clip=${clip%/}
  name=$(basename "$(dirname "$clip")")
  map=$from/data/${name}_seed${seed}.mrvm
  [[ -f $map ]] || { echo "localise_replay.sh: no map $map for $clip (wrong --seed?)" >&2; exit 1; }
  "$MRVS_BUILD/bin/localise_probe" --replay "$clip" --map "$map" --config "$MRVS_ROOT/config/euroc.yaml" \
      --map-config "$MRVS_ROOT/config/map_indoor.yaml" "${sets[@]}" 2>/dev/null | grep '^REPLAY ' >>"$out/replay.txt" \
    || { echo "localise_replay.sh: localise_probe --replay failed on $clip" >&2; exit 1; }
done
{
  echo "from $from, seed $seed, overrides: ${sets[*]:-none}, revision $(git -C "$MRVS_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  "$(command -v /usr/bin/python3 || command -v python3)" "$MRVS_ROOT/scripts/lib/replay_summary.py" "$out/replay.txt"
} | tee "$out/summary.txt"
