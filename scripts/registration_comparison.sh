#!/usr/bin/env bash
# The cloud's registration against PCL's on the same localisation requests (issue 30). For
# each shared EuRoC trajectory: short clips from evenly spread start instants (realistic
# preset, one seed; the clips and maps of scripts/localisation_experiment.sh, shareable with
# --data), the edge's VIO with the cloud in process on each (localise_probe --dump: every
# localisation request the edge sent, with the simulator's true T_map_odom, read by the
# measurement only), then localise_compare on every request of the trajectory: ours (the
# Localiser), FPFH + sample consensus + GICP (PCL, global), and from one offset start per
# request the fine stages (ours, PCL's GICP, NDT, point-to-plane ICP). One thread
# (OMP_NUM_THREADS=1). Writes OUT/REPORT.md. With --dumps-only it stops after the dumps (the
# input of scripts/localise_replay.sh).
#
# Usage: scripts/registration_comparison.sh [--out DIR] [--seed N] [--per-trajectory K]
#                                           [--duration S] [--offset F] [--data DIR]
#                                           [--start-m M] [--start-deg D] [--dumps-only]
#   defaults: build/registration_comparison, seed 2, 4 clips per trajectory of 12 s, offset
#   0.5 (the starts of localisation_experiment.sh with K clips), fine starts 0.2 m / 5 deg off.
# Environment: MRVS_SHARED_DIR (default tests/, which holds data/euroc_groundtruth/).
set -euo pipefail
source "$(dirname "${BASH_SOURCE[0]}")/lib/build.sh"

out=$MRVS_BUILD/registration_comparison
seed=2
per=4
duration=12
offset=0.5
data=""
start_m=0.2
start_deg=5
dumps_only=false
while [[ $# -gt 0 ]]; do
  case $1 in
    --out) out=${2:?}; shift 2 ;;
    --seed) seed=${2:?}; shift 2 ;;
    --per-trajectory) per=${2:?}; shift 2 ;;
    --duration) duration=${2:?}; shift 2 ;;
    --offset) offset=${2:?}; shift 2 ;;
    --data) data=${2:?}; shift 2 ;;
    --start-m) start_m=${2:?}; shift 2 ;;
    --start-deg) start_deg=${2:?}; shift 2 ;;
    --dumps-only) dumps_only=true; shift ;;
    -h|--help) sed -n '2,18p' "${BASH_SOURCE[0]}"; exit 0 ;;
    *) echo "registration_comparison.sh: unknown argument '$1' (see --help)" >&2; exit 2 ;;
  esac
done
shared=${MRVS_SHARED_DIR:-$MRVS_ROOT/tests}
[[ -d $shared/data/euroc_groundtruth ]] || { echo "registration_comparison.sh: missing $shared/data/euroc_groundtruth" >&2; exit 1; }
mrvs_build --target dataset_simulator map_builder localise_probe localise_compare
bin=$MRVS_BUILD/bin
data=${data:-$out/data}
rm -rf "$out/dumps" "$out/compare"  # never report an earlier run's requests
mkdir -p "$out/dumps" "$out/compare" "$data"
started=$SECONDS
export OMP_NUM_THREADS=1
cfg=$MRVS_ROOT/config
for trajectory in "$shared"/data/euroc_groundtruth/*.txt; do
  name=$(basename "$trajectory" .txt)
  length=$(awk 'NR > 1 && $1 !~ /^#/ { if (!t0) t0 = $1; t = $1 } END { printf "%.0f", t - t0 }' "$trajectory")
  map=$data/${name}_seed${seed}.mrvm
  mkdir -p "$out/dumps/$name"
  for ((i = 0; i < per; i++)); do
    start=$(awk -v i="$i" -v f="$offset" -v l="$length" -v k="$per" 'BEGIN { printf "%.1f", 3 + (i + f) * (l - 18) / k }')
    clip=$data/${name}_seed${seed}_start${start}
    step "$name from $start s (seed $seed; $((SECONDS - started)) s so far)"
    [[ -d $clip/mav0 ]] || "$bin/dataset_simulator" --trajectory "$trajectory" --profile indoor --preset realistic \
        --start "$start" --duration "$duration" --seed "$seed" --out "$clip" --log-level warn
    [[ -f $map ]] || "$bin/map_builder" --input "$clip/mav0/pointcloud0/data.ply" \
        --config "$cfg/map_indoor.yaml" --out "$map" --log-level warn >/dev/null
    "$bin/localise_probe" --dataset "$clip" --map "$map" --config "$cfg/euroc.yaml" \
        --map-config "$cfg/map_indoor.yaml" --dump "$out/dumps/$name/start$start" >"$out/dumps/$name/probe_start$start.txt" 2>&1 \
      || { echo "localise_probe failed on $clip (log: $out/dumps/$name/probe_start$start.txt)" >&2; exit 1; }
  done
  $dumps_only && continue
  step "$name: comparing ($((SECONDS - started)) s so far)"
  echo "localise_compare --replay $out/dumps/$name --map $map --map-config config/map_indoor.yaml --start-m $start_m --start-deg $start_deg" \
      >"$out/compare/${name}_command.txt"
  "$bin/localise_compare" --replay "$out/dumps/$name" --map "$map" --map-config "$cfg/map_indoor.yaml" \
      --start-m "$start_m" --start-deg "$start_deg" >"$out/compare/$name.txt"
done

if $dumps_only; then
  echo "registration_comparison: dumps in $out/dumps, maps in $data ($((SECONDS - started)) s)"
  exit 0
fi
step "report"
"$(command -v /usr/bin/python3 || command -v python3)" - "$out" "$seed" "$per" "$duration" "$offset" "$start_m" "$start_deg" "$(git -C "$MRVS_ROOT" rev-parse --short HEAD 2>/dev/null || echo unknown)" <<'PY'
import glob, os, re, statistics as st, sys
out, seed, per, duration, offset, start_m, start_deg, rev = sys.argv[1:9]
line = re.compile(r"^COMPARE (\S+) (\S+) (correct|WRONG|no answer) error ([0-9.eE+-]+|nan) m yaw ([0-9.eE+-]+|nan) tilt ([0-9.eE+-]+|nan) deg ([0-9.eE+-]+) ms")
rows, setup = {}, {}
for f in sorted(glob.glob(os.path.join(out, "compare", "*.txt"))):
    if f.endswith("_command.txt"):
        continue
    for l in open(f):
        m = line.match(l)
        if m:
            rows.setdefault(m.group(2), []).append((m.group(3), float(m.group(4)), max(float(m.group(5)), float(m.group(6))), float(m.group(7))))
        elif l.startswith("SETUP_S_"):
            k, v = l.split(": ")
            setup.setdefault(k, []).append(float(v))
q = lambda v, p: sorted(v)[min(len(v) - 1, int(p * len(v)))] if v else float("nan")
desc = {"ours": "ours: branch and bound + 4-DoF point-to-plane + verdict (global)",
        "fpfh_sac": "PCL: FPFH + SampleConsensusPrerejective + GICP (global)",
        "ours_fine": "ours: 4-DoF point-to-plane alone (fine, from the offset start)",
        "gicp": "PCL: GeneralizedIterativeClosestPoint (fine, 6-DoF)",
        "ndt": "PCL: NormalDistributionsTransform (fine, 6-DoF)",
        "point_to_plane": "PCL: IterativeClosestPointWithNormals (fine, 6-DoF)"}
with open(os.path.join(out, "REPORT.md"), "w") as f:
    n = len(next(iter(rows.values()))) if rows else 0
    f.write(f"# Registration: ours against PCL on {n} localisation requests\n\n")
    f.write(f"Revision {rev}. Seed {seed}, {per} clips per shared trajectory of {duration} s (start offset {offset}), realistic "
            "preset, shipped configs; every request the edge sent (localise_probe --dump), with the simulator's truth. "
            f"Fine methods start {start_m} m and {start_deg} deg off the truth (a direction turning per request). "
            "One thread. Correct: within 10 cm and 2 deg (yaw and tilt); precise: within 3 cm and 0.5 deg; "
            "PCL answers when it converged with the localiser's min_fitness. Commands: compare/*_command.txt; "
            "produced by scripts/registration_comparison.sh.\n\n")
    f.write("| method | answered | correct | precise | wrong | error median (correct) | time median | time p95 |\n|---|---|---|---|---|---|---|---|\n")
    for k in ["ours", "fpfh_sac", "ours_fine", "gicp", "ndt", "point_to_plane"]:
        r = rows.get(k, [])
        if not r:
            continue
        ans = [x for x in r if x[0] != "no answer"]
        ok = [x for x in ans if x[0] == "correct"]
        prec = [x for x in ok if x[1] <= 0.03 and x[2] <= 0.5]
        em = f"{100 * st.median([x[1] for x in ok]):.1f} cm / {st.median([x[2] for x in ok]):.2f} deg" if ok else "-"
        ms = [x[3] for x in r]
        f.write(f"| {desc[k]} | {len(ans)}/{len(r)} | {len(ok)} | {len(prec)} | {len(ans) - len(ok)} | {em} | "
                f"{st.median(ms):.0f} ms | {q(ms, 0.95):.0f} ms |\n")
    for k, v in sorted(setup.items()):
        f.write(f"\n- {k}: median {st.median(v):.1f} s over {len(v)} maps (per map, once)")
    f.write("\n")
print(open(os.path.join(out, "REPORT.md")).read())
PY
echo "registration_comparison: done in $((SECONDS - started)) s, report $out/REPORT.md"
