#!/usr/bin/env bash
# cloud_server and edge_client as two processes over Fast DDS on loopback
# (config/dds/loopback.xml): starts the server on MAP in the background, runs edge_client on
# SEQUENCE with the map, stops the server (by PID, also on failure). Leaves server.log,
# edge.txt (the client's report) and trajectory.txt in OUT. Called by demo.sh inside a
# private network namespace (unshare -n, lo up) when root.
#
# Usage: scripts/lib/map_run.sh MAP SEQUENCE OUT EDGE_CONFIG MAP_CONFIG [edge_client args...]
# Environment: MRVS_MAP_WAIT (s the client waits for the map at start, default 20),
# MRVS_SERVER_LOG_LEVEL (cloud_server's, default warn).
set -euo pipefail
[[ $# -ge 5 ]] || { sed -n '8p' "${BASH_SOURCE[0]}" >&2; exit 2; }
map=$1 sequence=$2 out=$3 edge_config=$4 map_config=$5
shift 5
root=$(cd "$(dirname "${BASH_SOURCE[0]}")/../.." && pwd)
bin=${MRVS_BUILD_DIR:-$root/build}/bin
profile=$root/config/dds/loopback.xml
mkdir -p "$out"

server_pid=""
stop_server() {
  [[ -n $server_pid ]] || return 0
  kill -TERM "$server_pid" 2>/dev/null || return 0
  for _ in $(seq 50); do kill -0 "$server_pid" 2>/dev/null || { wait "$server_pid" 2>/dev/null; return 0; }; sleep 0.1; done
  kill -KILL "$server_pid" 2>/dev/null
  return 0
}
trap stop_server EXIT
trap 'exit 130' INT TERM

"$bin/cloud_server" --map "$map" --dds-profile "$profile" --config "$map_config" --stats-period 0 \
    --log-level "${MRVS_SERVER_LOG_LEVEL:-warn}" >"$out/server.log" 2>&1 &
server_pid=$!
"$bin/edge_client" --dataset "$sequence" --config "$edge_config" --output "$out/trajectory.txt" \
    --dds-profile "$profile" --map-wait "${MRVS_MAP_WAIT:-20}" --threads 1 "$@" >"$out/edge.txt"
stop_server
server_pid=""
grep -q '^REQUESTS_ANSWERED:' "$out/server.log" || { echo "map_run.sh: cloud_server did not stop cleanly:" >&2; cat "$out/server.log" >&2; exit 1; }
