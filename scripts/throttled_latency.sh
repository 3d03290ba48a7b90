#!/usr/bin/env bash
# The two-host link (network namespaces over a veth pair) shaped by tc tbf on both ends,
# optionally with random packet loss (nftables). Measures the achieved rate first (one TCP
# transfer), then runs cloud_server and link_probe across it with a tshark capture and prints
# one table: rays per frame, bytes per frame (application and wire), wire overhead, RTT
# percentiles, frames lost. Always removes what it created.
#
# Usage: sudo scripts/throttled_latency.sh [--mbytes-per-s 1.66] [--burst BYTES] [--loss PERCENT]
#            [--frames N] [--rate HZ] [--profile two_hosts|lossy_link]
#   --burst    token bucket depth in bytes (default 1600: about one 1514 B frame, so a
#              6.4 KB batch cannot pass at line rate)
#   --loss     drop that percentage of packets in each direction (default 0); the profile
#              then defaults to lossy_link (10 ms heartbeats, no response delays)
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/netns.sh"
source "$MRVS_ROOT/scripts/lib/link_experiment.sh"

mbytes=1.66 burst=1600 loss=0 frames=300 rate=20 profile=""
while [[ $# -gt 0 ]]; do
  case $1 in
    --mbytes-per-s) mbytes=$2; shift 2 ;;
    --burst) burst=$2; shift 2 ;;
    --loss) loss=$2; shift 2 ;;
    --frames) frames=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --profile) profile=$2; shift 2 ;;
    -h|--help) sed -n '2,13p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "throttled_latency.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
[[ $mbytes =~ ^[0-9]+(\.[0-9]+)?$ ]] || { echo "throttled_latency.sh: --mbytes-per-s '$mbytes' is not a positive number" >&2; exit 2; }
[[ $burst =~ ^[0-9]+$ && $burst -ge 1514 ]] || { echo "throttled_latency.sh: --burst '$burst' must be an integer >= 1514 (one full Ethernet frame)" >&2; exit 2; }
[[ $loss =~ ^[0-9]+$ && $loss -le 50 ]] || { echo "throttled_latency.sh: --loss '$loss' must be an integer percentage 0..50" >&2; exit 2; }
[[ -z $profile ]] && { [[ $loss -gt 0 ]] && profile=lossy_link || profile=two_hosts; }
[[ -f $MRVS_ROOT/config/dds/$profile.xml ]] || { echo "throttled_latency.sh: no profile config/dds/$profile.xml" >&2; exit 2; }
netns_require_root
command -v tshark >/dev/null || { echo "throttled_latency.sh: 'tshark' missing: run scripts/install_deps.sh" >&2; exit 1; }
command -v python3 >/dev/null || { echo "throttled_latency.sh: 'python3' missing: run scripts/install_deps.sh" >&2; exit 1; }

link_prepare
netns_create
mbit=$(awk -v m="$mbytes" 'BEGIN { printf "%.3f", m * 8 }')
step "shaping both ends: tbf rate ${mbit}mbit (${mbytes} MB/s) burst ${burst} B"
netns_shape "$mbit" "$burst"
rate_measured=$(netns_measure_rate 3000000)
read -r goodput wire <<<"$rate_measured"
printf 'achieved rate (3 MB over TCP): goodput %.3f MB/s, on the wire %.3f MB/s (asked %s MB/s)\n' \
    "$(awk -v g="$goodput" 'BEGIN { print g / 1e6 }')" "$(awk -v w="$wire" 'BEGIN { print w / 1e6 }')" "$mbytes"
if [[ $loss -gt 0 ]]; then
  step "dropping $loss % of the packets leaving each host (nftables)"
  netns_loss "$loss"
fi
out=$MRVS_BUILD/link_results/throttled_${mbytes}MBps_loss${loss}
step "cloud_server in $NS_CLOUD, link_probe in $NS_EDGE ($frames frames at $rate Hz, profile $profile)"
link_run "$profile" "$frames" "$rate" "$out" 1
link_table "$out" "throttled link: ${mbytes} MB/s, burst ${burst} B, loss ${loss} %, profile $profile"
