# Sourced by the link experiment scripts: two "hosts" on this machine as network namespaces
# joined by a veth pair, with optional shaping (tc tbf) and loss (nftables), processes
# started inside them, and a cleanup that always runs (trap). Requires root, iproute2,
# nftables. Nothing here touches the root namespace's interfaces or routes.
#
# Hosts: cloud 10.77.0.1 (namespace $NS_CLOUD, device $DEV_CLOUD)
#        edge  10.77.0.2 (namespace $NS_EDGE,  device $DEV_EDGE)

NETNS_TAG=mrvs$$
NS_CLOUD=${NETNS_TAG}c
NS_EDGE=${NETNS_TAG}e
DEV_CLOUD=${NETNS_TAG}vc
DEV_EDGE=${NETNS_TAG}ve
IP_CLOUD=10.77.0.1
IP_EDGE=10.77.0.2
NETNS_PIDS=()

netns_require_root() {
  if [[ $(id -u) -ne 0 ]]; then
    echo "$(basename "$0"): needs root (it creates network namespaces); run with sudo" >&2
    exit 2
  fi
  for tool in ip tc nft; do
    command -v "$tool" >/dev/null || { echo "$(basename "$0"): '$tool' missing: run scripts/install_deps.sh" >&2; exit 1; }
  done
}

# netns_stop PID [SIGNAL]: sends SIGNAL (default TERM), waits up to 5 s, then SIGKILL.
netns_stop() {
  local pid=$1 signal=${2:-TERM} i
  kill -"$signal" "$pid" 2>/dev/null || return 0
  for ((i = 0; i < 50; i++)); do kill -0 "$pid" 2>/dev/null || return 0; sleep 0.1; done
  kill -KILL "$pid" 2>/dev/null
  return 0
}

netns_cleanup() {
  set +e  # runs from the EXIT trap: must get to the end whatever fails
  local pid
  for pid in "${NETNS_PIDS[@]}"; do netns_stop "$pid"; done
  ip netns del "$NS_CLOUD" 2>/dev/null
  ip netns del "$NS_EDGE" 2>/dev/null
}

# netns_create: the two namespaces, the veth pair, addresses, loopback up.
netns_create() {
  trap 'netns_cleanup 2>/dev/null' EXIT  # bash 5.2 may print a spurious "wait_for: No record" here
  trap 'exit 130' INT TERM
  ip netns add "$NS_CLOUD"
  ip netns add "$NS_EDGE"
  ip link add "$DEV_CLOUD" type veth peer name "$DEV_EDGE"
  ip link set "$DEV_CLOUD" netns "$NS_CLOUD"
  ip link set "$DEV_EDGE" netns "$NS_EDGE"
  ip -n "$NS_CLOUD" addr add "$IP_CLOUD/24" dev "$DEV_CLOUD"
  ip -n "$NS_EDGE" addr add "$IP_EDGE/24" dev "$DEV_EDGE"
  for ns in "$NS_CLOUD" "$NS_EDGE"; do ip -n "$ns" link set lo up; done
  ip -n "$NS_CLOUD" link set "$DEV_CLOUD" up
  ip -n "$NS_EDGE" link set "$DEV_EDGE" up
}

# netns_shape RATE_MBIT BURST_BYTES: token bucket on both ends (each direction shaped).
netns_shape() {
  local rate=$1 burst=$2
  ip netns exec "$NS_CLOUD" tc qdisc add dev "$DEV_CLOUD" root tbf rate "${rate}mbit" burst "$burst" latency 400ms
  ip netns exec "$NS_EDGE" tc qdisc add dev "$DEV_EDGE" root tbf rate "${rate}mbit" burst "$burst" latency 400ms
}

# netns_loss PERCENT: drop that share of outgoing IPv4 packets on both ends (this kernel has
# no netem; nftables' numgen gives uniform random drops).
netns_loss() {
  local percent=$1 ns
  for ns in "$NS_CLOUD" "$NS_EDGE"; do
    ip netns exec "$ns" nft -f - <<NFT
table ip mrvs_loss {
  chain out {
    type filter hook output priority 0; policy accept;
    numgen random mod 100 < $percent drop
  }
}
NFT
  done
}

# netns_run NS LOGFILE CMD...: starts CMD in namespace NS in the background and remembers
# its PID for the cleanup; the PID is in NETNS_LAST_PID (call it directly, not in $(...):
# a subshell would lose the PID list).
netns_run() {
  local ns=$1 log=$2
  shift 2
  # The child must not run this script's EXIT trap when it ends: reset traps and exec.
  (trap - EXIT INT TERM; exec ip netns exec "$ns" "$@") >"$log" 2>&1 &
  NETNS_LAST_PID=$!
  disown "$NETNS_LAST_PID"  # tracked here, stopped with netns_stop (not bash job control)
  NETNS_PIDS+=("$NETNS_LAST_PID")
}

# netns_qdisc_bytes NS DEV: bytes the root qdisc of DEV has sent so far.
netns_qdisc_bytes() {
  ip netns exec "$1" tc -s qdisc show dev "$2" | awk '$1 == "Sent" { print $2; exit }'
}

# netns_measure_rate BYTES: one TCP transfer of BYTES from the cloud to the edge host; prints
# "GOODPUT_BYTES_PER_S WIRE_BYTES_PER_S" (wire: Ethernet bytes the cloud qdisc sent over the
# transfer time). Run it before netns_loss: drops would measure TCP's recovery, not the link.
netns_measure_rate() {
  local bytes=$1 port=5399 result wire0 wire1
  local tool=$MRVS_ROOT/scripts/lib/measure_rate.py
  wire0=$(netns_qdisc_bytes "$NS_CLOUD" "$DEV_CLOUD")
  result=$(ip netns exec "$NS_EDGE" timeout 60 python3 "$tool" recv "$port" 30 &
           sleep 0.3
           ip netns exec "$NS_CLOUD" timeout 60 python3 "$tool" send "$IP_EDGE" "$port" "$bytes" >&2
           wait)
  wire1=$(netns_qdisc_bytes "$NS_CLOUD" "$DEV_CLOUD")
  awk -v r="$result" -v w="$((wire1 - wire0))" 'BEGIN {
    split(r, f, " "); if (f[2] <= 0) exit 1; printf "%.0f %.0f\n", f[1] / f[2], w / f[2] }'
}
