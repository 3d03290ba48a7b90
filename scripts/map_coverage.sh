#!/usr/bin/env bash
# The prior map's coverage of the true surface (issue 31): generates an indoor sequence's
# survey map (the whole source trajectory; 2 s of images), builds the voxel map with the
# shipped config/map_indoor.yaml, and measures with map_coverage the share of the true
# surface voxels at 0.01 m within 3 m of the whole camera path that the map's 0.01 m level
# holds. Also reports the map's size and the builder's time and peak memory.
#
# Usage: scripts/map_coverage.sh [--trajectory NAME] [--seed N] [--out DIR] [dataset_simulator flags...]
#   e.g. scripts/map_coverage.sh --set map.model=scanner --set map.station_spacing_m=3
# Defaults: V1_01_easy, seed 1, preset realistic, out /tmp/mrvs_map_coverage (removed unless --keep).
# Prints KEY: value lines; the same go to OUT/report.txt.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"

trajectory=V1_01_easy seed=1 out=/tmp/mrvs_map_coverage keep=0
extra=()
while (($#)); do
  case $1 in
    --trajectory) trajectory=$2; shift 2 ;;
    --seed) seed=$2; shift 2 ;;
    --out) out=$2; shift 2 ;;
    --keep) keep=1; shift ;;
    *) extra+=("$1"); shift ;;
  esac
done
traj=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}/data/euroc_groundtruth/$trajectory.txt
[[ -f $traj ]] || { echo "map_coverage.sh: no trajectory $traj" >&2; exit 2; }
mrvs_build --target dataset_simulator map_builder map_coverage >/dev/null
mkdir -p "$out"
((keep)) || trap 'rm -rf "$out/sequence" "$out/map.mrvm"' EXIT
report=$out/report.txt
{
  echo "TRAJECTORY: $trajectory"
  echo "SEED: $seed"
  echo "FLAGS: --preset realistic ${extra[*]:-}"
  echo "REVISION: $(git -C "$MRVS_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)"
  /usr/bin/time -f "GENERATE_WALL_S: %e\nGENERATE_PEAK_KB: %M" "$MRVS_BUILD/bin/dataset_simulator" \
      --trajectory "$traj" --profile indoor --preset realistic --start 20 --duration 2 --seed "$seed" \
      "${extra[@]}" --out "$out/sequence" --overwrite --log-level warn 2>&1 | grep -E "MAP_POINTS|SECONDS_MAP|GENERATE"
  echo "PLY_BYTES: $(stat -c %s "$out/sequence/mav0/pointcloud0/data.ply")"
  "$MRVS_BUILD/bin/map_builder" --input "$out/sequence/mav0/pointcloud0/data.ply" \
      --config "$MRVS_ROOT/config/map_indoor.yaml" --out "$out/map.mrvm" --log-level warn |
      grep -E "LEVEL_0_POINTS|MAP_BYTES|SECONDS_TOTAL|PEAK_MEMORY" | sed 's/^/BUILDER_/'
  "$MRVS_BUILD/bin/map_coverage" --dataset "$out/sequence" --map "$out/map.mrvm" --whole-trajectory
} | tee "$report"
