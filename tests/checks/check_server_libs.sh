#!/usr/bin/env bash
# Fails if cloud_server needs a run-time library its container image does not install
# (docker/Dockerfile: Fast DDS, yaml-cpp, spdlog, absl): e.g. PCL or OpenMP pulled in with the
# offline map builder's code (mrvs::map_build), which the server must not link.
set -euo pipefail
bin=${1:?usage: check_server_libs.sh CLOUD_SERVER_BINARY}
needed=$(readelf -d "$bin" | awk '/NEEDED/ { gsub(/[][]/, "", $5); print $5 }')
bad=$(grep -E '^lib(pcl|opencv|gomp|ceres|vtk|glog)' <<<"$needed" || true)
if [[ -n $bad ]]; then
  echo "$bin needs libraries the cloud_server image does not install (link mrvs::map, not mrvs::map_build):"
  echo "$bad"
  exit 1
fi
echo "cloud_server needs only: $(tr '\n' ' ' <<<"$needed")"
