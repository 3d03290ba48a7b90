#!/usr/bin/env bash
# The paper's evaluation on generated data, one command. Installs what it needs and builds
# first, then for each sequence and seed: generates it (realistic preset), builds its map,
# runs edge_client plain (--no-map) and against cloud_server over Fast DDS on loopback (inside
# a private network namespace when root) with the map, with ground-truth query poses and with
# each fixed level, all from the paper's start (estimator.alignment.source gt_noisy: the ground
# truth plus 2 cm), and once more with the map from the map-based start (the product's
# default: no ground truth, the cloud's localisation, in real time); evaluates every
# trajectory; runs the two-host and 1.66 MB/s link experiments when root; writes
# results/<date>/REPORT.md with tables and figures from the result files
# (scripts/lib/make_report.py).
#
# Usage: scripts/run_experiments.sh [--quick] [--out DIR] [--seeds "1 2 3"] [--data DIR] [--sequences "A B"]
#                                  [--edge-args "ARGS"] [--variants "V ..."]
#   --quick   one 30 s indoor sequence (V1_01_easy), one seed, loopback link only
#             (about 5 minutes here once built)
#   default   every trajectory in tests/data/euroc_groundtruth/ full length plus the outdoor
#             profile on a 2.2 km route, seeds 1 2 3 (hours on this machine)
#   --data    where the generated sequences and maps go (default OUT/data); a sequence folder
#             <name>_seed<N> already there is used as it is
#   --sequences  only these (names of the trajectories, e.g. "V1_02_medium V2_01_easy", or outdoor)
#   --edge-args  added to every edge_client run, e.g. "--stage1-mode ray_depth --set
#             estimator.map.uncertainty_scale=2" (recorded in meta.txt and the report)
#   --variants   only these runs per sequence (of: plain map map_start gt fixed), e.g. "map
#             map_start" for the map-based start against the paper's; no link experiments
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"
source "$MRVS_ROOT/scripts/lib/outdoor_route.sh"

quick=false
link=true
out=""
seeds=""
data=""
only=""
edge_args=""
variants="plain map map_start gt fixed"
while [[ $# -gt 0 ]]; do
  case $1 in
    --quick) quick=true; shift ;;
    --out) out=${2:?--out needs a folder}; shift 2 ;;
    --seeds) seeds=${2:?--seeds needs a list}; shift 2 ;;
    --data) data=${2:?--data needs a folder}; shift 2 ;;
    --sequences) only=${2:?--sequences needs names}; shift 2 ;;
    --edge-args) edge_args=${2?--edge-args needs a (quoted) list}; shift 2 ;;
    --variants) variants=${2:?--variants needs a list}; link=false; shift 2 ;;
    -h|--help) sed -n '2,22p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "run_experiments.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
for v in $variants; do
  [[ " plain map map_start gt fixed " == *" $v "* ]] || { echo "run_experiments.sh: --variants: no variant '$v' (plain map map_start gt fixed)" >&2; exit 2; }
done
wants() { [[ " $variants " == *" $1 "* ]]; }
shared=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}
[[ -d $shared/data/euroc_groundtruth ]] || { echo "run_experiments.sh: missing $shared/data/euroc_groundtruth" >&2; exit 1; }
out=${out:-$MRVS_ROOT/results/$(date -u +%Y-%m-%d)$($quick && echo -quick)}
if $quick; then seeds=${seeds:-1}; else seeds=${seeds:-"1 2 3"}; fi

mrvs_build --target experiment_tools
bin=$MRVS_BUILD/bin
data=${data:-$out/data}
mkdir -p "$out/runs" "$data"
started=$SECONDS

# sequences: name profile trajectory-or-route duration
sequences=()
if $quick; then
  sequences+=("V1_01_easy indoor $shared/data/euroc_groundtruth/V1_01_easy.txt 30")
else
  for f in "$shared"/data/euroc_groundtruth/*.txt; do sequences+=("$(basename "$f" .txt) indoor $f 0"); done
  sequences+=("outdoor outdoor - 0")
fi
if [[ -n $only ]]; then
  chosen=()
  for name in $only; do
    match=""
    for entry in "${sequences[@]}"; do [[ ${entry%% *} == "$name" ]] && match=$entry; done
    [[ -n $match ]] || { echo "run_experiments.sh: --sequences: no sequence '$name' (have: $(printf '%s ' "${sequences[@]%% *}"))" >&2; exit 2; }
    chosen+=("$match")
  done
  sequences=("${chosen[@]}")
fi

in_netns() {  # runs "$@" in a private network namespace when root (nothing leaves the machine)
  if [[ $(id -u) -eq 0 ]] && command -v unshare >/dev/null; then
    unshare -n bash -c 'ip link set lo up && exec "$@"' in_netns "$@"
  else
    "$@"
  fi
}

run_variant() {  # run_variant SEQ_DIR MAP RESULT_DIR CONFIG MAP_CONFIG VARIANT [edge args...]
  local seq=$1 map=$2 dir=$3 config=$4 map_config=$5 variant=$6
  shift 6
  # shellcheck disable=SC2206  # --edge-args is a word list by design
  set -- "$@" $edge_args
  mkdir -p "$dir"
  if [[ $variant == plain ]]; then
    echo "edge_client --dataset $seq --config $config --no-map --threads 1 $*" >"$dir/command.txt"
    "$bin/edge_client" --dataset "$seq" --config "$config" --output "$dir/trajectory.txt" --no-map --threads 1 \
        --log-level warn --progress 0 "$@" >"$dir/edge.txt"
  else
    echo "scripts/lib/map_run.sh $map $seq OUT $config $map_config $* --lock-poses OUT/locks.txt" >"$dir/command.txt"
    in_netns "$MRVS_ROOT/scripts/lib/map_run.sh" "$map" "$seq" "$dir" "$config" "$map_config" \
        --log-level warn --progress 0 "$@" --lock-poses "$dir/locks.txt"
  fi
  local gt=$seq/mav0/state_groundtruth_estimate0/data.csv
  "$bin/evaluate_trajectory" --est "$dir/trajectory.txt" --gt "$gt" --align se3 --log-level warn >"$dir/eval.txt"
  # The map-based start: where the cloud placed the edge (the first lock's own placement, not
  # moved by a later lock), against the truth at that frame.
  local at
  at=$(awk '$1 == "LOCALISED_AT_T_NS:" {print $2}' "$dir/edge.txt")
  if [[ $variant == map_start && -n $at && $at != 0 ]]; then
    "$bin/evaluate_trajectory" --est "$dir/locks.txt" --gt "$gt" --align none --at "$at" --log-level warn \
        | grep -E '^POSE_(HEADING_)?ERROR_AT_' >"$dir/alignment.txt"
  fi
  printf '  %-22s ATE %s m (SE3 %s m)\n' "$variant" "$(awk '$1 == "ATE_RMSE_m:" {print $2}' "$dir/eval.txt")" \
      "$(awk '$1 == "ATE_RMSE_SE3_m:" {print $2}' "$dir/eval.txt")"
}

for entry in "${sequences[@]}"; do
  read -r name profile source duration <<<"$entry"
  if [[ $profile == indoor ]]; then
    config=$MRVS_ROOT/config/euroc.yaml map_config=$MRVS_ROOT/config/map_indoor.yaml
    export MRVS_MAP_WAIT=20
    gen=(--trajectory "$source" --profile indoor)
  else
    config=$MRVS_ROOT/config/kaist.yaml map_config=$MRVS_ROOT/config/map_outdoor.yaml
    export MRVS_MAP_WAIT=180  # the server loads a 3 GB map first
    gen=("${MRVS_OUTDOOR_ROUTE[@]}")  # 2.2 km (scripts/lib/outdoor_route.sh)
  fi
  [[ $duration == 0 ]] || gen+=(--duration "$duration")
  for seed in $seeds; do
    seq=$data/${name}_seed$seed
    step "$name, seed $seed: generate, build the map ($((SECONDS - started)) s so far)"
    [[ -d $seq/mav0 ]] || "$bin/dataset_simulator" "${gen[@]}" --preset realistic --seed "$seed" --out "$seq" \
        --log-level warn
    [[ -f $seq.mrvm && -f $seq.map_builder.txt ]] || "$bin/map_builder" --input "$seq/mav0/pointcloud0/data.ply" --config "$map_config" \
        --out "$seq.mrvm" --log-level warn >"$seq.map_builder.txt"
    dir=$out/runs/$name/seed$seed
    mkdir -p "$dir"
    echo "$seq/mav0/state_groundtruth_estimate0/data.csv" >"$dir/groundtruth.csv"
    paper=(--set estimator.alignment.source=gt_noisy)  # the paper's start: ground truth + 2 cm
    ! wants plain || run_variant "$seq" "$seq.mrvm" "$dir/plain" "$config" "$map_config" plain "${paper[@]}"
    ! wants map || run_variant "$seq" "$seq.mrvm" "$dir/map" "$config" "$map_config" map "${paper[@]}"
    ! wants map_start || run_variant "$seq" "$seq.mrvm" "$dir/map_start" "$config" "$map_config" map_start --realtime
    ! wants gt || run_variant "$seq" "$seq.mrvm" "$dir/gt" "$config" "$map_config" gt --query-pose-source gt "${paper[@]}"
    [[ $profile == indoor ]] && wants fixed || continue  # outdoor: no level ablation (each run is minutes long)
    for r in $(awk -F': ' '/^LEVEL_[0-9]+_RESOLUTION_M:/ {print $2}' "$seq.map_builder.txt"); do
      run_variant "$seq" "$seq.mrvm" "$dir/fixed_$r" "$config" "$map_config" "fixed $r m" --fixed-resolution "$r" \
          "${paper[@]}"
    done
  done
done

if [[ $(id -u) -eq 0 ]] && ! $quick && $link; then
  step "link experiments (two hosts, 1.66 MB/s)"
  mkdir -p "$out/link"
  "$MRVS_ROOT/scripts/two_hosts.sh" --frames 600 >"$out/link/two_hosts.txt"
  "$MRVS_ROOT/scripts/throttled_latency.sh" --frames 600 >"$out/link/two_hosts_1.66MBps.txt"
fi

{
  echo "DATE: $(date -u +%Y-%m-%dT%H:%M:%SZ)"
  echo "GIT_REVISION: $(git -C "$MRVS_ROOT" rev-parse --short HEAD)$(git -C "$MRVS_ROOT" diff --quiet || echo -dirty)"
  echo "MODE: $($quick && echo quick || echo full)"
  echo "SEEDS: ${seeds// /,}"
  echo "SEQUENCES: $(printf '%s ' "${sequences[@]%% *}")"
  echo "EDGE_ARGS: ${edge_args:-none}"
  echo "VARIANTS: ${variants// /,}"
  echo "FASTDDS: $(dpkg-query -W -f='${Version}' libfastrtps2.9 2>/dev/null || echo unknown)"
  echo "COMPILER: $(c++ --version | head -1 | tr ' ' '_')"
  echo "CPU_CORES: $(nproc)"
  echo "WALL_S: $((SECONDS - started))"
} >"$out/meta.txt"

step "report"
"$(command -v /usr/bin/python3 || command -v python3)" "$MRVS_ROOT/scripts/lib/make_report.py" "$out"
echo "run_experiments: done in $((SECONDS - started)) s"
