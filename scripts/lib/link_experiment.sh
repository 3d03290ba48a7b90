# Sourced by two_hosts.sh and throttled_latency.sh: data preparation, the cloud_server +
# link_probe run across the two namespaces, the capture, and the table.
# Needs scripts/lib/build.sh and scripts/lib/netns.sh sourced first.

LINK_DATA=$MRVS_BUILD/link_data
LINK_SEQUENCE=$LINK_DATA/V1_01_sim
LINK_MAP=$LINK_DATA/V1_01_sim.mrvm

# link_prepare: builds the tools and, unless present, a 15 s synthetic sequence and its map.
link_prepare() {
  mrvs_build --target dataset_simulator map_builder cloud_server link_probe >/dev/null
  local traj=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}/data/euroc_groundtruth/V1_01_easy.txt
  if [[ ! -f $LINK_SEQUENCE/sim0/request.yaml ]]; then
    step "generating a 15 s sequence for the link ($LINK_SEQUENCE)"
    "$MRVS_BUILD/bin/dataset_simulator" --trajectory "$traj" --duration 15 --out "$LINK_SEQUENCE" --overwrite \
        --log-level warn >/dev/null
  fi
  if [[ ! -f $LINK_MAP || $LINK_MAP -ot $LINK_SEQUENCE/mav0/pointcloud0/data.ply ]]; then
    step "building its map ($LINK_MAP)"
    "$MRVS_BUILD/bin/map_builder" --input "$LINK_SEQUENCE/mav0/pointcloud0/data.ply" \
        --config "$MRVS_ROOT/config/map_indoor.yaml" --out "$LINK_MAP" --log-level warn >/dev/null
  fi
}

# link_run PROFILE FRAMES RATE_HZ OUT_DIR [CAPTURE=0|1]: cloud_server in the cloud namespace,
# link_probe in the edge namespace (optionally captured with tshark on the edge device).
link_run() {
  local profile=$1 frames=$2 rate=$3 out=$4 capture=${5:-0}
  mkdir -p "$out"
  rm -f "$out/capture.pcap" "$out/probe.txt"  # never report an earlier run's figures
  netns_run "$NS_CLOUD" "$out/server.log" "$MRVS_BUILD/bin/cloud_server" --map "$LINK_MAP" \
      --dds-profile "$MRVS_ROOT/config/dds/$profile.xml" --dds-interface "$IP_CLOUD" --dds-peer "$IP_EDGE" \
      --config "$MRVS_ROOT/config/map_indoor.yaml" --stats-period 0
  local server=$NETNS_LAST_PID
  local tshark_pid=""
  if [[ $capture == 1 ]]; then
    netns_run "$NS_EDGE" "$out/tshark.log" tshark -q -i "$DEV_EDGE" -w "$out/capture.pcap" \
        -f "udp portrange $(dds_port_range 42) or (ip[6:2] & 0x1fff != 0)"
    tshark_pid=$NETNS_LAST_PID
    sleep 2
  fi
  # In the background + wait: a signal to this script is handled at once (bash defers traps
  # while a foreground child runs), and the cleanup stops the probe too.
  (trap - EXIT INT TERM; exec ip netns exec "$NS_EDGE" "$MRVS_BUILD/bin/link_probe" --sequence "$LINK_SEQUENCE" \
      --dds-profile "$MRVS_ROOT/config/dds/$profile.xml" --dds-interface "$IP_EDGE" --dds-peer "$IP_CLOUD" \
      --frames "$frames" --rate "$rate" --timeout-ms 1000 --map-wait 30 --log-level warn) >"$out/probe.txt" &
  local probe=$!
  NETNS_PIDS+=("$probe")
  local status=0
  wait "$probe" || status=$?
  [[ $status -eq 0 ]] || { echo "link_probe failed (exit $status); server log: $out/server.log" >&2; return "$status"; }
  [[ -n $tshark_pid ]] && { sleep 1; netns_stop "$tshark_pid" INT; }
  netns_stop "$server"
  return 0
}

# dds_port_range DOMAIN: the RTPS ports of a DDS domain (PB 7400 + DG 250 * domain, 250
# ports); with the IP fragments (offset != 0) that carry no UDP header, what to capture.
dds_port_range() { echo "$((7400 + 250 * $1))-$((7400 + 250 * $1 + 249))"; }

# value FILE KEY: the value of a "KEY: value" line.
value() { awk -v k="$2:" '$1 == k { print $2 }' "$1"; }

# link_wire_bytes OUT_DIR: bytes on the wire (Ethernet frames) per direction during the
# frame phase of the probe, from the capture: prints "UP DOWN DISCOVERY_BYTES".
link_wire_bytes() {
  local out=$1
  local t0 t1
  t0=$(value "$out/probe.txt" FIRST_FRAME_EPOCH_NS)
  t1=$(value "$out/probe.txt" LAST_FRAME_EPOCH_NS)
  tshark -r "$out/capture.pcap" -T fields -e frame.time_epoch -e ip.src -e frame.len 2>/dev/null |
    awk -v t0="$t0" -v t1="$t1" -v edge="$IP_EDGE" '
      { t = $1 * 1e9; if (t >= t0 && t <= t1 + 5e8) { if ($2 == edge) up += $3; else down += $3 } else other += $3 }
      END { printf "%d %d %d\n", up, down, other }'
}

# link_table OUT_DIR LABEL: one table of the run.
link_table() {
  local out=$1 label=$2 p=$1/probe.txt
  local frames raw_up raw_down
  frames=$(value "$p" FRAMES)
  raw_up=$(value "$p" RAW_BYTES_UP_PER_FRAME)
  raw_down=$(value "$p" RAW_BYTES_DOWN_PER_FRAME)
  printf '\n%s\n' "$label"
  printf '  %-34s %s\n' "frames / lost (timeouts)" "$frames / $(value "$p" TIMEOUTS)"
  printf '  %-34s %s (hits %s)\n' "rays per frame" "$(value "$p" RAYS_PER_FRAME)" "$(value "$p" HITS_PER_FRAME)"
  printf '  %-34s %s up, %s down\n' "raw payload bytes per frame" "$raw_up" "$raw_down"
  printf '  %-34s %s up, %s down\n' "DDS sample bytes per frame" "$(value "$p" SAMPLE_BYTES_UP_PER_FRAME)" \
      "$(value "$p" SAMPLE_BYTES_DOWN_PER_FRAME)"
  if [[ -f $out/capture.pcap ]]; then
    read -r up down other < <(link_wire_bytes "$out")
    awk -v u="$up" -v d="$down" -v n="$frames" -v ru="$raw_up" -v rd="$raw_down" -v o="$other" 'BEGIN {
      printf "  %-34s %.0f up, %.0f down\n", "wire bytes per frame (Ethernet)", u / n, d / n;
      printf "  %-34s %.3f (up %.3f, down %.3f)\n", "wire bytes / raw payload", (u + d) / n / (ru + rd), u / n / ru, d / n / rd;
      printf "  %-34s %.1f KB\n", "outside the frames (discovery...)", o / 1000 }'
  fi
  printf '  %-34s p50 %s  p95 %s  p99 %s  max %s\n' "RTT ms" "$(value "$p" RTT_P50_MS)" "$(value "$p" RTT_P95_MS)" \
      "$(value "$p" RTT_P99_MS)" "$(value "$p" RTT_MAX_MS)"
}
