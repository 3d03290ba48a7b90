# Sourced by scripts/containers.sh: podman set-up, the offline base image, the image builds,
# the two-container run through docker/compose.yaml, its report and the clean-up.
# Needs scripts/lib/build.sh (MRVS_ROOT, MRVS_BUILD, step) and scripts/lib/link_experiment.sh
# (value) sourced first.

CT_COMPOSE=$MRVS_ROOT/docker/compose.yaml
CT_BASE_IMAGE=docker.io/library/debian:bookworm   # what `FROM debian:bookworm` resolves to
CT_IMAGE_PREFIX=localhost/mrvs

# ct_timed NAME CMD...: runs CMD, appends "NAME SECONDS" to $CT_TIMINGS.
ct_timed() {
  local name=$1 start=$SECONDS
  shift
  "$@"
  printf '%-18s %5d s\n' "$name" $((SECONDS - start)) >>"$CT_TIMINGS"
}

# ct_configure_podman DIR: the containers.conf that works on this kind of machine
# (containers.md): runc, and ulimits root may set here (nofile hard limit 20000).
ct_configure_podman() {
  mkdir -p "$1"
  cat >"$1/containers.conf" <<'EOF'
[containers]
default_ulimits = ["nofile=20000:20000", "nproc=32768:32768"]

[engine]
runtime = "runc"
EOF
  export CONTAINERS_CONF=$1/containers.conf
  podman info --format '{{.Host.OCIRuntime.Name}} {{.Store.GraphDriverName}} {{.Host.NetworkBackend}}' \
      | awk '{ printf "podman: runtime %s, storage %s, network %s\n", $1, $2, $3 }'
}

# ct_apt_mirror: the Debian mirror apt uses here (deb822 sources first, then sources.list).
ct_apt_mirror() {
  local uri=""
  if compgen -G '/etc/apt/sources.list.d/*.sources' >/dev/null; then
    uri=$(awk '/^URIs:/ && $2 !~ /security/ { print $2; exit }' /etc/apt/sources.list.d/*.sources)
  fi
  if [[ -z $uri && -f /etc/apt/sources.list ]]; then
    uri=$(awk '$1 == "deb" && $0 !~ /security/ { for (i = 2; i <= NF; i++) if ($i ~ /^http/) { print $i; exit } }' \
        /etc/apt/sources.list)
  fi
  echo "${uri:-http://deb.debian.org/debian}"
}

# ct_base_image ROOTFS_DIR: debian:bookworm from debootstrap (minbase), unless present.
ct_base_image() {
  if podman image exists "$CT_BASE_IMAGE"; then
    echo "$CT_BASE_IMAGE already present"
    return 0
  fi
  local rootfs=$1 log=$1.log
  rm -rf "$rootfs"
  if ! debootstrap --variant=minbase bookworm "$rootfs" "$(ct_apt_mirror)" >"$log" 2>&1; then
    tail -n 20 "$log" >&2
    echo "containers.sh: debootstrap failed (log: $log); check that apt reaches $(ct_apt_mirror)" >&2
    return 1
  fi
  rm -rf "$rootfs"/var/cache/apt/archives/*.deb "$rootfs"/var/lib/apt/lists/*
  tar -C "$rootfs" -c . | podman import - "$CT_BASE_IMAGE" >/dev/null
  rm -rf "$rootfs"
  echo "imported $CT_BASE_IMAGE ($(ct_size "$CT_BASE_IMAGE"))"
}

# ct_stage_binaries BIN_DIR: the binaries the `prebuilt` stage copies (docker/prebuilt/).
ct_stage_binaries() {
  local dst=$MRVS_ROOT/docker/prebuilt
  mkdir -p "$dst"
  cp "$1/cloud_server" "$1/edge_client" "$1/evaluate_trajectory" "$dst/"
}

# ct_build_image NAME BINARIES: localhost/mrvs/NAME:latest from the Dockerfile's NAME stage.
ct_build_image() {
  local name=$1 log=$out/build_$1.log
  if ! podman build -f "$MRVS_ROOT/docker/Dockerfile" --target "$name" --build-arg "BINARIES=$2" \
      -t "$CT_IMAGE_PREFIX/$name:latest" "$MRVS_ROOT" >"$log" 2>&1; then
    tail -n 30 "$log" >&2
    echo "containers.sh: building the $name image failed (log: $log)" >&2
    return 1
  fi
  echo "$CT_IMAGE_PREFIX/$name:latest ($(ct_size "$CT_IMAGE_PREFIX/$name:latest"))"
}

ct_size() { podman image inspect --format '{{.Size}}' "$1" | awk '{ printf "%.0f MB", $1 / 1e6 }'; }

ct_image_sizes() {
  local name
  for name in "$@"; do printf '%-18s %s\n' "size_$name" "$(ct_size "$CT_IMAGE_PREFIX/$name:latest")"; done
}

# ct_start_service DIR: the Docker API of podman (`podman system service`) on a socket of our
# own, for docker-compose (podman-compose 1.0.3 cannot give a container a fixed address).
# Sets DOCKER_HOST and CT_SERVICE_PID; ct_cleanup stops it by PID.
ct_start_service() {
  local sock=$1/podman.sock
  rm -f "$sock"
  podman system service --time=0 "unix://$sock" >"$1/service.log" 2>&1 &
  CT_SERVICE_PID=$!
  export DOCKER_HOST=unix://$sock
  local _
  for _ in $(seq 100); do
    [[ -S $sock ]] && curl -sf --unix-socket "$sock" http://d/_ping >/dev/null 2>&1 && return 0
    sleep 0.1
  done
  cat "$1/service.log" >&2
  echo "containers.sh: podman system service did not come up on $sock" >&2
  return 1
}

# ct_compose PROJECT DATA ARGS...: docker-compose on docker/compose.yaml for this project.
ct_compose() {
  local project=$1 data=$2
  shift 2
  MRVS_DATA=$data MRVS_IMAGE_PREFIX=$CT_IMAGE_PREFIX docker-compose --ansi never -p "$project" -f "$CT_COMPOSE" "$@"
}

# ct_container PROJECT SERVICE: the container name compose gave the service.
ct_container() {
  podman ps -a --filter "label=com.docker.compose.project=$1" --filter "label=com.docker.compose.service=$2" \
      --format '{{.Names}}' | head -n 1
}

# ct_run PROJECT DATA OUT TIMEOUT_S: starts both services, waits for the client, stops the
# server (SIGTERM: it prints its counters), keeps both logs in OUT.
ct_run() {
  local project=$1 data=$2 out=$3 timeout=$4
  ct_compose "$project" "$data" up -d --no-build >"$out/compose_up.log" 2>&1 || {
    cat "$out/compose_up.log" >&2; echo "containers.sh: compose up failed" >&2; return 1; }
  local server edge
  server=$(ct_container "$project" cloud_server)
  edge=$(ct_container "$project" edge_client)
  [[ -n $server && -n $edge ]] || { cat "$out/compose_up.log" >&2; echo "containers.sh: containers not created" >&2; return 1; }
  echo "cloud_server: $server ($(podman inspect --format '{{range .NetworkSettings.Networks}}{{.IPAddress}}{{end}}' "$server"))"
  echo "edge_client:  $edge ($(podman inspect --format '{{range .NetworkSettings.Networks}}{{.IPAddress}}{{end}}' "$edge"))"
  # Waited for in the background: the `wait` builtin lets Ctrl-C / SIGTERM reach the trap at once.
  timeout "$timeout" podman wait "$edge" >"$out/edge_exit_code" 2>&1 &
  CT_WAITER_PID=$!
  local code=timeout
  if wait "$CT_WAITER_PID"; then code=$(tail -n 1 "$out/edge_exit_code"); fi
  CT_WAITER_PID=""
  podman stop -t 10 "$server" >/dev/null || true
  podman logs "$edge" >"$out/edge.txt" 2>"$out/edge.log" || true
  podman logs "$server" >"$out/server.log" 2>&1 || true
  grep -E '^\[.*(progress|frame)' "$out/edge.log" | tail -n 2 || true
  if [[ $code != 0 ]]; then
    tail -n 30 "$out/edge.log" >&2
    echo "containers.sh: edge_client ended with '$code' (log: $out/edge.log)" >&2
    return 1
  fi
}

# ct_report OUT DATA: ATE of the client's trajectory, its link figures, the server's count.
# Fails when there is no trajectory or the server answered no request.
ct_report() {
  local out=$1 data=$2 traj=$2/out/trajectory.txt
  [[ -s $traj ]] || { echo "containers.sh: the client wrote no trajectory ($traj)" >&2; return 1; }
  "$MRVS_BUILD/bin/evaluate_trajectory" --est "$traj" --gt "$data/sequence/mav0/state_groundtruth_estimate0/data.csv" \
      --align se3 --log-level warn >"$out/ate.txt"
  local k
  for k in ATE_RMSE_m ATE_RMSE_SE3_m; do printf '%-30s %s\n' "$k" "$(value "$out/ate.txt" "$k")"; done
  for k in FRAMES RAYS_PER_FRAME ACCEPTED_PER_FRAME PAYLOAD_UP_BYTES_PER_FRAME PAYLOAD_DOWN_BYTES_PER_FRAME \
           RTT_MS_MEDIAN RTT_MS_P95 MAP_TIMEOUTS FRAMES_WITHOUT_MAP FRAME_MS_MEDIAN; do
    printf '%-30s %s\n' "$k" "$(value "$out/edge.txt" "$k")"
  done
  local answered
  answered=$(value "$out/server.log" REQUESTS_ANSWERED)
  printf '%-30s %s\n' "server REQUESTS_ANSWERED" "${answered:-none}"
  [[ ${answered:-0} -gt 0 ]] || { echo "containers.sh: cloud_server answered no request (log: $out/server.log)" >&2; return 1; }
}

# ct_remove_stale: the containers and networks of earlier runs whose script is gone (killed
# before its trap ran): their fixed subnet would block this run.
ct_remove_stale() {
  local project pid
  for project in $(podman network ls --format '{{.Labels}}' 2>/dev/null \
                   | grep -oE 'com\.docker\.compose\.project=mrvs_ci_[0-9]+' | cut -d= -f2 | sort -u); do
    pid=${project#mrvs_ci_}
    kill -0 "$pid" 2>/dev/null && continue
    echo "removing the leftovers of an earlier run ($project)"
    ct_cleanup_project "$project"
  done
}

# ct_cleanup_project PROJECT: removes the project's containers and networks.
ct_cleanup_project() {
  local ids
  ids=$(podman ps -aq --filter "label=com.docker.compose.project=$1" 2>/dev/null) || ids=""
  [[ -z $ids ]] || podman rm -f -t 5 $ids >/dev/null 2>&1 || true
  podman network ls -q --filter "label=com.docker.compose.project=$1" 2>/dev/null \
      | xargs -r podman network rm -f >/dev/null 2>&1 || true
}

# ct_cleanup PROJECT: removes the project's containers and network whatever state they are
# in, and stops the API service (by PID).
ct_cleanup() {
  [[ -z ${CT_WAITER_PID:-} ]] || kill "$CT_WAITER_PID" 2>/dev/null || true
  if command -v podman >/dev/null; then ct_cleanup_project "$1"; fi
  if [[ -n ${CT_SERVICE_PID:-} ]]; then
    kill -TERM "$CT_SERVICE_PID" 2>/dev/null && wait "$CT_SERVICE_PID" 2>/dev/null
    CT_SERVICE_PID=""
  fi
  rm -rf "$MRVS_ROOT/docker/prebuilt"
  return 0
}
