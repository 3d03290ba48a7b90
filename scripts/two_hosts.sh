#!/usr/bin/env bash
# Two hosts on one machine: network namespaces joined by a veth pair (cloud 10.77.0.1, edge
# 10.77.0.2), cloud_server in one and link_probe (the edge side) in the other, over the
# two-host unicast profile. Prints the link table. Always removes what it created.
#
# Usage: sudo scripts/two_hosts.sh [--frames N] [--rate HZ] [--profile two_hosts|lossy_link] [--capture]
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/netns.sh"
source "$MRVS_ROOT/scripts/lib/link_experiment.sh"

frames=300 rate=20 profile=two_hosts capture=0
while [[ $# -gt 0 ]]; do
  case $1 in
    --frames) frames=$2; shift 2 ;;
    --rate) rate=$2; shift 2 ;;
    --profile) profile=$2; shift 2 ;;
    --capture) capture=1; shift ;;
    -h|--help) sed -n '2,7p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "two_hosts.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
netns_require_root
link_prepare
netns_create
out=$MRVS_BUILD/link_results/two_hosts
step "cloud_server in $NS_CLOUD, link_probe in $NS_EDGE ($frames frames at $rate Hz, profile $profile)"
link_run "$profile" "$frames" "$rate" "$out" "$capture"
link_table "$out" "two hosts (veth), profile $profile"
