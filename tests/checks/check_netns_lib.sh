#!/usr/bin/env bash
# scripts/lib/netns.sh does what the link experiments rely on: two namespaces joined by a
# veth pair, tbf shaping whose achieved rate matches the request, and a cleanup that removes
# the namespaces and the processes it started even when the script fails. Needs root, ip, tc,
# python3; skipped (77) otherwise.
set -uo pipefail
root=$1
[[ $(id -u) -eq 0 ]] || { echo "skipped: needs root"; exit 77; }
for t in ip tc nft python3; do command -v "$t" >/dev/null || { echo "skipped: no $t"; exit 77; }; done
ip netns list >/dev/null 2>&1 || { echo "skipped: no network namespaces here"; exit 77; }
log=$(mktemp)
trap 'rm -f "$log"' EXIT

# A failing experiment: shapes, measures, starts a long process, then fails (exit 3).
(
  set -euo pipefail
  MRVS_ROOT=$root
  source "$root/scripts/lib/netns.sh"
  netns_create
  echo "NAMESPACES: $NS_CLOUD $NS_EDGE"
  netns_shape 13.28 1600
  rate=$(netns_measure_rate 1000000)
  read -r goodput wire <<<"$rate"
  echo "RATE: $goodput $wire"
  netns_run "$NS_CLOUD" /dev/null sleep 300
  echo "PID: $NETNS_LAST_PID"
  false
  echo "not reached"
) >"$log" 2>&1
rc=$?
cat "$log"
fail=0
[[ $rc -ne 0 ]] || { echo "FAIL: the failing script exited 0"; fail=1; }
read -r _ ns_cloud ns_edge < <(grep '^NAMESPACES:' "$log")
read -r _ goodput wire < <(grep '^RATE:' "$log")
read -r _ pid < <(grep '^PID:' "$log")
grep -q 'not reached' "$log" && { echo "FAIL: set -e did not stop the script"; fail=1; }
for ns in $ns_cloud $ns_edge; do
  ip netns list | grep -qw "$ns" && { echo "FAIL: namespace $ns left behind"; ip netns del "$ns"; fail=1; }
done
[[ -n ${pid:-} ]] || { echo "FAIL: no process was started"; fail=1; }
[[ -n ${pid:-} ]] && kill -0 "$pid" 2>/dev/null && { echo "FAIL: process $pid left running"; kill -KILL "$pid"; fail=1; }
# 13.28 Mbit/s = 1.66 MB/s of Ethernet bytes; TCP goodput is ~95 % of it.
awk -v w="${wire:-0}" -v g="${goodput:-0}" 'BEGIN { exit !(w > 0.8 * 1.66e6 && w < 1.05 * 1.66e6 && g < w) }' ||
  { echo "FAIL: achieved rate goodput ${goodput:-?} B/s, wire ${wire:-?} B/s, expected about 1.66e6 on the wire"; fail=1; }
exit $fail
