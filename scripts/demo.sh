#!/usr/bin/env bash
# The main job, end to end, on built-in data. Installs what it needs and builds first.
#
#   1. generate a synthetic EuRoC-format sequence (stereo PNGs, IMU, ground truth, prior
#      LiDAR point cloud) along the real EuRoC V1_01_easy trajectory with dataset_simulator
#      (realistic preset: noise, exposure changes, map changes),
#   2. build the multi-resolution voxel map of its point cloud (map_builder -> .mrvm),
#   3. start cloud_server on it and run edge_client against it over Fast DDS on loopback
#      (inside a private network namespace when root), in real time and without ground truth:
#      the cloud's localisation service places the edge in its map, then the paper's two-stage
#      update runs,
#   4. run edge_client again as plain VIO (--no-map, in its own odometry frame),
#   5. print the time to localise and the alignment's error against the simulator's truth, the
#      ATE and heading error of both against the ground truth (plain VIO: SE(3)-aligned only),
#      the payload per frame, the round trip and the per-frame timing columns, and write a
#      trajectory plot (PNG).
#
# Usage: scripts/demo.sh [--out DIR] [--duration S]   (defaults: build/demo, 30 s)
# Environment: MRVS_SHARED_DIR (default tests/, which holds data/euroc_groundtruth/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/link_experiment.sh"  # value

out=$MRVS_BUILD/demo
duration=30
while [[ $# -gt 0 ]]; do
  case $1 in
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --duration) duration=${2:?--duration needs seconds}; shift 2 ;;
    -h|--help) sed -n '2,15p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "demo.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done

trajectory=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}/data/euroc_groundtruth/V1_01_easy.txt
[[ -f $trajectory ]] || { echo "demo.sh: missing $trajectory (the shared EuRoC ground truth)" >&2; exit 1; }

mrvs_build --target demo_tools
bin=$MRVS_BUILD/bin
mkdir -p "$out"
sequence=$out/V1_01_sim

step "1. generate a ${duration} s synthetic sequence along V1_01_easy (realistic preset)"
"$bin/dataset_simulator" --trajectory "$trajectory" --profile indoor --preset realistic --duration "$duration" \
    --seed 1 --out "$sequence" --overwrite --log-level warn

step "2. build its multi-resolution voxel map"
map=$out/V1_01_sim.mrvm
"$bin/map_builder" --input "$sequence/mav0/pointcloud0/data.ply" --config "$MRVS_ROOT/config/map_indoor.yaml" \
    --out "$map" --log-level warn >"$out/map_builder.txt"
grep -E '^(RAW_POINTS|LEVEL_[0-9]+_(RESOLUTION_M|POINTS)|MAP_BYTES|SECONDS_TOTAL):' "$out/map_builder.txt"

step "3. cloud_server + edge_client with the map over Fast DDS (loopback)"
runner=("$MRVS_ROOT/scripts/lib/map_run.sh" "$map" "$sequence" "$out/map" "$MRVS_ROOT/config/euroc.yaml"
        "$MRVS_ROOT/config/map_indoor.yaml" --realtime --log-level info --progress 5 --lock-poses "$out/map/locks.txt")
if [[ $(id -u) -eq 0 ]] && command -v unshare >/dev/null; then
  # A private network namespace: nothing the participants send can leave the machine.
  unshare -n bash -c 'ip link set lo up && exec "$@"' map_run "${runner[@]}"
else
  "${runner[@]}"  # the loopback profile alone keeps traffic on 127.0.0.1
fi

step "4. edge_client as plain VIO (--no-map)"
mkdir -p "$out/plain"
"$bin/edge_client" --dataset "$sequence" --config "$MRVS_ROOT/config/euroc.yaml" --output "$out/plain/trajectory.txt" \
    --no-map --threads 1 --log-level info --progress 5 >"$out/plain/edge.txt"

step "5. results"
gt=$sequence/mav0/state_groundtruth_estimate0/data.csv
ate() {  # ate TRAJ KEY
  "$bin/evaluate_trajectory" --est "$1" --gt "$gt" --align se3 --log-level warn | awk -v k="$2:" '$1 == k { print $2 }'
}
e=$out/map/edge.txt
# Where the cloud placed the edge (the first lock's own placement), against the simulator's truth
# at that frame.
if [[ $(value "$e" LOCALISED) -ge 1 ]]; then
  "$bin/evaluate_trajectory" --est "$out/map/locks.txt" --gt "$gt" --align none --at "$(value "$e" LOCALISED_AT_T_NS)" \
      --log-level warn >"$out/map/alignment.txt"
  echo "localised in the map after $(value "$e" LOCALISED_AFTER_S) s of VIO" \
       "($(value "$e" LOCALISATION_REQUESTS) requests of $(value "$e" LOCALISATION_REQUEST_BYTES) B," \
       "cloud $(value "$e" LOCALISATION_CLOUD_MS_MEDIAN) ms median):" \
       "alignment error $(value "$out/map/alignment.txt" POSE_ERROR_AT_M) m," \
       "$(value "$out/map/alignment.txt" POSE_ERROR_AT_DEG) deg (heading $(value "$out/map/alignment.txt" POSE_HEADING_ERROR_AT_DEG) deg)"
else
  echo "the cloud did not place the edge in its map within the ${duration} s: its trajectory is plain VIO in the" \
       "odometry frame ($(value "$e" LOCALISATION_REQUESTS) localisation requests)"
fi
echo
printf '%-28s %12s %12s\n' "" "with map" "plain VIO"
for k in ATE_RMSE_m ATE_RMSE_SE3_m ATE_HEADING_RMSE_deg; do
  # Plain VIO is in its own odometry frame: only the aligned figure means anything.
  plain=$(ate "$out/plain/trajectory.txt" $k)
  [[ $k == ATE_RMSE_SE3_m ]] || plain=n/a
  printf '%-28s %12.4f %12s\n' "$k" "$(ate "$out/map/trajectory.txt" $k)" "$plain"
done
for k in FRAME_MS_MEDIAN A_IMAGE_MS_MEDIAN B_TRACKING_MS_MEDIAN C_UPDATE_MS_MEDIAN D_SELECTION_MS_MEDIAN E_RAYS_MS_MEDIAN; do
  printf '%-28s %12s %12s\n' "$k" "$(value "$e" $k)" "$(value "$out/plain/edge.txt" $k)"
done
echo
for k in RAYS_PER_FRAME ACCEPTED_PER_FRAME REGISTERED_PER_FRAME PAYLOAD_UP_BYTES_PER_FRAME PAYLOAD_DOWN_BYTES_PER_FRAME \
         PAYLOAD_BYTES_PER_FRAME_MAX RTT_MS_MEDIAN RTT_MS_P95 MAP_TIMEOUTS FRAMES_WITHOUT_MAP; do
  printf '%-28s %12s\n' "$k" "$(value "$e" $k)"
done
plot=$out/trajectories.png
# Debian's python (install_deps.sh installs its matplotlib), not a python earlier on PATH.
"$(command -v /usr/bin/python3 || command -v python3)" "$MRVS_ROOT/scripts/lib/plot_trajectories.py" "$plot" "$gt" "with map=$out/map/trajectory.txt" \
    "plain VIO=$out/plain/trajectory.txt"
requests=$(value "$e" MAP_REQUESTS)
awk -v r="$requests" 'BEGIN { exit !(r > 0) }' || { echo "demo.sh: the client sent no map requests" >&2; exit 1; }
echo
echo "demo: OK. Sequence in $sequence, reports in $out/{map,plain}/edge.txt, plot $plot"
