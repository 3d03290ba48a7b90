#!/usr/bin/env bash
# cloud_server and edge_client in two containers (podman; docker/compose.yaml through docker-compose) on the demo's
# sequence: installs podman (apt), builds a Debian 12 base image offline (debootstrap from the
# apt mirror this machine uses; no registry pull), builds the cloud_server and edge_client
# images (docker/Dockerfile), generates the sequence and its map, runs both containers on one
# internal bridge network (UDP unicast between the two container addresses only), then prints
# the client's ATE and link figures and the server's request count. Always removes the
# containers and the network it created, also on failure or Ctrl-C; the images stay cached.
# Fails when the client does not finish with a trajectory or the server served no request.
#
# Usage: sudo scripts/containers.sh [--duration S] [--out DIR] [--from-source] [--timeout S]
#   --duration S    length of the generated sequence (default 30, the demo's)
#   --out DIR       data, logs and the step timings (default build/containers)
#   --from-source   compile the project inside the image (builder stage) instead of copying
#                   this tree's binaries (same Debian 12 libraries; CI copies, it built them)
#   --timeout S     longest wait for the client (default 900)
#   --reuse-data    keep the sequence and map of an earlier run in OUT when both are there
# Environment: MRVS_SHARED_DIR (default tests/, which holds data/euroc_groundtruth/), MRVS_BUILD_DIR.
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/link_experiment.sh"  # value
source "$MRVS_ROOT/scripts/lib/containers.sh"

duration=30 out=$MRVS_BUILD/containers binaries=prebuilt timeout=900 reuse=0
while [[ $# -gt 0 ]]; do
  case $1 in
    --duration) duration=${2:?--duration needs seconds}; shift 2 ;;
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --from-source) binaries=builder; shift ;;
    --timeout) timeout=${2:?--timeout needs seconds}; shift 2 ;;
    --reuse-data) reuse=1; shift ;;
    -h|--help) sed -n '2,18p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "containers.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
if [[ $(id -u) -ne 0 ]]; then
  echo "containers.sh: needs root (podman as root with runc; see docker/README.md)." >&2
  echo "  Fix: sudo scripts/containers.sh" >&2
  exit 1
fi
trajectory=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}/data/euroc_groundtruth/V1_01_easy.txt
[[ -f $trajectory ]] || { echo "containers.sh: missing $trajectory (the shared EuRoC ground truth)" >&2; exit 1; }

mkdir -p "$out"
out=$(cd "$out" && pwd)
CT_TIMINGS=$out/steps.txt
: >"$CT_TIMINGS"
project=mrvs_ci_$$
trap 'ct_cleanup "$project"' EXIT
trap 'exit 130' INT TERM

step "1. podman, runc, debootstrap, docker-compose (apt)"
ct_timed install "$MRVS_ROOT/scripts/install_deps.sh" --containers
ct_configure_podman "$out/podman"
ct_remove_stale
ct_start_service "$out/podman"

step "2. Debian 12 base image without a registry (debootstrap from $(ct_apt_mirror))"
ct_timed base_image ct_base_image "$out/rootfs"

step "3. binaries"
if [[ $binaries == prebuilt ]]; then
  ct_timed host_build mrvs_build --target demo_tools
  ct_stage_binaries "$MRVS_BUILD/bin"
else
  ct_timed host_build mrvs_build --target evaluate_trajectory dataset_simulator map_builder
fi

step "4. images (docker/Dockerfile, binaries: $binaries)"
for image in cloud_server edge_client; do
  ct_timed "image_$image" ct_build_image "$image" "$binaries"
done
ct_image_sizes cloud_server edge_client | tee -a "$CT_TIMINGS"

step "5. the demo's sequence (${duration} s along V1_01_easy, realistic preset) and its map"
data=$out/data
rm -rf "$data/out"
mkdir -p "$data/out"
if [[ $reuse == 1 && -f $data/sequence/sim0/request.yaml && -f $data/map.mrvm ]]; then
  echo "reusing $data/sequence and $data/map.mrvm"
else
  ct_timed sequence "$MRVS_BUILD/bin/dataset_simulator" --trajectory "$trajectory" --profile indoor --preset realistic \
      --duration "$duration" --seed 1 --out "$data/sequence" --overwrite --log-level warn
  ct_timed map "$MRVS_BUILD/bin/map_builder" --input "$data/sequence/mav0/pointcloud0/data.ply" \
      --config "$MRVS_ROOT/config/map_indoor.yaml" --out "$data/map.mrvm" --log-level warn >"$out/map_builder.txt"
fi

step "6. cloud_server and edge_client in two containers (compose project $project)"
ct_timed run ct_run "$project" "$data" "$out" "$timeout"

step "7. results"
ct_report "$out" "$data" | tee "$out/summary.txt"
echo
echo "step timings (s) and image sizes:"
cat "$CT_TIMINGS"
