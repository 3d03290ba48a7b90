#!/usr/bin/env bash
# cloud_server and link_probe on loopback (config/dds/loopback.xml): starts the server in the
# background, replays FRAMES query batches of SEQUENCE at RATE Hz, stops the server (by PID,
# also on failure) and leaves server.log and probe.txt in OUT. Called by demo.sh inside a
# private network namespace (unshare -n, lo up) when root.
#
# Usage: scripts/lib/loopback_link.sh MAP SEQUENCE OUT FRAMES RATE_HZ
set -euo pipefail
[[ $# -eq 5 ]] || { sed -n '7p' "${BASH_SOURCE[0]}" >&2; exit 2; }
map=$1 sequence=$2 out=$3 frames=$4 rate=$5
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

"$bin/cloud_server" --map "$map" --dds-profile "$profile" --config "$root/config/map_indoor.yaml" \
    --stats-period 0 --log-level warn >"$out/server.log" 2>&1 &
server_pid=$!
"$bin/link_probe" --sequence "$sequence" --dds-profile "$profile" --frames "$frames" --rate "$rate" \
    --timeout-ms 1000 --map-wait 20 --log-level warn >"$out/probe.txt"
stop_server
server_pid=""
grep -q '^REQUESTS_ANSWERED:' "$out/server.log" || { echo "loopback_link.sh: cloud_server did not stop cleanly:" >&2; cat "$out/server.log" >&2; exit 1; }
