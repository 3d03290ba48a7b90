#!/usr/bin/env bash
# The main job, end to end, on built-in data. Installs what it needs and builds first.
#
# What the project can do so far (this script grows with every issue):
#   1. generate a synthetic EuRoC-format sequence (stereo PNGs, IMU, ground truth, prior
#      LiDAR point cloud) along the real EuRoC V1_01_easy trajectory with dataset_simulator,
#   2. check it with the edge client's own EuRoC reader (dataset_info),
#   3. build the multi-resolution voxel map of its point cloud (map_builder -> .mrvm),
#   4. start cloud_server on it and replay 200-ray query batches from the ground-truth camera
#      poses with link_probe over Fast DDS on loopback (inside a private network namespace
#      when root), print the link table, stop the server,
#   5. evaluate a stand-in "estimate" against its ground truth with evaluate_trajectory: the
#      ground truth with a known error (0.30 m offset plus a drift of 1 mm/s along y), so the
#      printed figures can be checked against the known answer.
# Later issues replace step 5 by the edge_client estimate with and without the map.
#
# Usage: scripts/demo.sh [--out DIR] [--duration S]   (defaults: build/demo, 10 s)
# Environment: MRVS_SHARED_DIR (default ../shared next to the repository).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/link_experiment.sh"  # link_table

out=$MRVS_BUILD/demo
duration=10
while [[ $# -gt 0 ]]; do
  case $1 in
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --duration) duration=${2:?--duration needs seconds}; shift 2 ;;
    -h|--help) sed -n '2,19p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "demo.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

trajectory=${MRVS_SHARED_DIR:-$MRVS_ROOT/../shared}/data/euroc_groundtruth/V1_01_easy.txt
[[ -f $trajectory ]] || { echo "demo.sh: missing $trajectory (the shared EuRoC ground truth)" >&2; exit 1; }

mrvs_build --target dataset_simulator dataset_info evaluate_trajectory map_builder cloud_server link_probe
bin=$MRVS_BUILD/bin
mkdir -p "$out"
sequence=$out/V1_01_sim

step "1. generate a ${duration} s synthetic sequence along V1_01_easy"
"$bin/dataset_simulator" --trajectory "$trajectory" --profile indoor --preset easy --duration "$duration" \
    --seed 1 --out "$sequence" --overwrite --log-level warn

step "2. read it back with the project's EuRoC reader"
"$bin/dataset_info" --dataset "$sequence" --log-level warn | grep -E '^(euroc|  cam0|  imu0|stereo|STEREO|IMU|GROUND|WARN)'

step "3. build its multi-resolution voxel map"
map=$out/V1_01_sim.mrvm
"$bin/map_builder" --input "$sequence/mav0/pointcloud0/data.ply" --config "$MRVS_ROOT/config/map_indoor.yaml" \
    --out "$map" --log-level warn >"$out/map_builder.txt"
grep -E '^(RAW_POINTS|LEVEL_[0-9]+_(RESOLUTION_M|POINTS)|MAP_BYTES|SECONDS_TOTAL):' "$out/map_builder.txt"

step "4. serve it with cloud_server and query it with link_probe over Fast DDS (loopback)"
frames=$(awk -v d="$duration" 'BEGIN { n = int(d * 20); print (n > 200 ? 200 : n) }')
runner=("$MRVS_ROOT/scripts/lib/loopback_link.sh" "$map" "$sequence" "$out/link" "$frames" 20)
if [[ $(id -u) -eq 0 ]] && command -v unshare >/dev/null; then
  # A private network namespace: nothing the participants send can leave the machine.
  unshare -n bash -c 'ip link set lo up && exec "$@"' loopback "${runner[@]}"
else
  "${runner[@]}"  # the loopback profile alone keeps traffic on 127.0.0.1
fi
link_table "$out/link" "cloud_server <-> link_probe on loopback ($frames frames at 20 Hz)"
timeouts=$(value "$out/link/probe.txt" TIMEOUTS)
hits=$(value "$out/link/probe.txt" HITS_PER_FRAME)
awk -v t="$timeouts" -v h="$hits" 'BEGIN { exit !(t == 0 && h > 0) }' || {
  echo "demo.sh: the link lost frames or found no map points (timeouts $timeouts, hits/frame $hits)" >&2; exit 1; }

step "5. evaluate a perturbed copy of its ground truth (known answer)"
gt=$sequence/mav0/state_groundtruth_estimate0/data.csv
est=$out/V1_01_sim_perturbed.txt
# EuRoC CSV (t_ns, p, q wxyz, ...) -> TUM (t_s, p, q xyzw) with offset (0.3, 0, 0) m and a
# drift of 1 mm/s along y. Stamps are split as text: awk numbers are doubles.
awk -F', *' '/^#/ { next }
  { n = length($1); secs = substr($1, 1, n - 9) "." substr($1, n - 8);
    if (!t0) t0 = secs; dt = secs - t0;
    printf "%s %.9f %.9f %s %s %s %s %s\n", secs, $2 + 0.3, $3 + 0.001 * dt, $4, $6, $7, $8, $5 }' "$gt" >"$est"
report=$("$bin/evaluate_trajectory" --est "$est" --gt "$gt" --align se3 --log-level warn --json "$out/eval.json")
grep -E '^(MATCHED_POSES|ATE_RMSE_m|ATE_RMSE_SE3_m):' <<<"$report"
raw=$(awk '/^ATE_RMSE_m:/ {print $2}' <<<"$report")
se3=$(awk '/^ATE_RMSE_SE3_m:/ {print $2}' <<<"$report")
# The known answer: the raw error is at least the 0.3 m offset; alignment removes the
# offset and leaves at most the drift.
awk -v r="$raw" -v s="$se3" -v d="$duration" 'BEGIN { exit !(r >= 0.3 && s <= 0.001 * d) }' || {
  echo "demo.sh: unexpected figures (raw $raw, SE(3) $se3)" >&2; exit 1; }
echo
echo "demo: OK. Sequence in $sequence, report in $out/eval.json"
