#!/usr/bin/env bash
# scripts/lib/make_report.py fills its tables from the result files, not from typed-in
# numbers: two result trees of random figures give two reports, each holding its own tree's
# numbers in the right table; a missing result file is an error naming it.
# check_report.sh ROOT OUT: instead, the report of a real run_experiments.sh run in OUT
# (.ci/run's --quick run) holds the numbers of that run's result files, every sequence.
set -uo pipefail
root=$1
tree=${2:-}
py=$(command -v /usr/bin/python3 || command -v python3)
tmp=$(mktemp -d)
trap 'rm -rf "$tmp"' EXIT
fail=0

make_tree() {  # make_tree DIR SEED: a results tree of random figures
  "$py" - "$1" "$2" <<'PY'
import os, random, sys
root, seed = sys.argv[1], int(sys.argv[2])
rng = random.Random(seed)
def w(path, keys):
    os.makedirs(os.path.dirname(path), exist_ok=True)
    with open(path, "w") as f:
        for k, v in keys.items():
            f.write(f"{k}: {v}\n")
w(os.path.join(root, "meta.txt"), {"DATE": "2026-01-01", "SEEDS": "1", "GIT_REVISION": f"r{seed}"})
for seq in ("SeqA", "SeqB"):
    for variant in ("plain", "map", "gt", "fixed_0.01", "fixed_0.02"):
        d = os.path.join(root, "runs", seq, "seed1", variant)
        w(os.path.join(d, "eval.txt"), {"ATE_RMSE_m": round(rng.uniform(0.01, 0.2), 4),
                                        "ATE_RMSE_SE3_m": round(rng.uniform(0.01, 0.2), 4)})
        edge = {k + "_MS_MEDIAN": round(rng.uniform(0.1, 9.0), 2)
                for k in ("A_IMAGE", "B_TRACKING", "C_UPDATE", "D_SELECTION", "E_RAYS", "FRAME")}
        edge.update({"FRAME_MS_P95": round(rng.uniform(10, 30), 2), "FRAME_INTERVAL_MS": 50.0, "RAYS_PER_FRAME": round(rng.uniform(1, 99), 1),
                     "PAYLOAD_UP_BYTES_PER_FRAME": rng.randint(100, 6000),
                     "PAYLOAD_DOWN_BYTES_PER_FRAME": rng.randint(10, 900),
                     "RTT_MS_MEDIAN": round(rng.uniform(0.5, 3), 3), "RTT_MS_P95": round(rng.uniform(3, 6), 3),
                     "MAP_TIMEOUTS": rng.randint(0, 9)})
        w(os.path.join(d, "edge.txt"), edge)
        with open(os.path.join(d, "command.txt"), "w") as f:
            f.write(f"edge_client {seq} {variant} seed{seed}\n")
    d = os.path.join(root, "runs", seq, "seed1", "map_start")  # the map-based start
    w(os.path.join(d, "eval.txt"), {"ATE_RMSE_m": round(rng.uniform(0.01, 0.2), 4)})
    w(os.path.join(d, "edge.txt"), {"LOCALISED": rng.randint(1, 3), "LOCALISED_AFTER_S": round(rng.uniform(1, 9), 2),
                                    "LOCKS_DOUBTED": rng.randint(0, 2), "LOCALISATION_FIXES": rng.randint(0, 30),
                                    "LOCALISATION_FIXES_REFUSED": rng.randint(0, 9)})
    w(os.path.join(d, "alignment.txt"), {"POSE_ERROR_AT_M": round(rng.uniform(0.0, 0.1), 4),
                                         "POSE_ERROR_AT_DEG": round(rng.uniform(0.0, 2.0), 3)})
    with open(os.path.join(d, "command.txt"), "w") as f:
        f.write(f"edge_client {seq} map_start seed{seed}\n")
PY
}

expect_row() {  # expect_row REPORT TREE SEQ: the Table II row of SEQ holds the tree's numbers
  local report=$1 tree=$2 seq=$3
  "$py" - "$report" "$tree" "$seq" <<'PY' || fail=1
import sys
report, tree, seq = sys.argv[1:]
def val(variant, key, f="eval.txt"):
    for line in open(f"{tree}/runs/{seq}/seed1/{variant}/{f}"):
        k, sep, v = line.partition(": ")  # real files also hold other lines
        if sep and k == key:
            return float(v)
    sys.exit(f"{key} missing from {tree}/runs/{seq}/seed1/{variant}/{f}")
p, m = val("plain", "ATE_RMSE_m"), val("map", "ATE_RMSE_m")
want = f"| {seq} | 1 | {100 * p:.2f} | {100 * m:.2f} | {m / p:.2f} |"
text = open(report).read()
if want not in text:
    sys.exit(f"Table II row missing from {report}: {want}")
g = val("gt", "ATE_RMSE_m")
if f"| {seq} | {100 * m:.2f} | {100 * g:.2f} |" not in text:
    sys.exit(f"Table III row of {seq} missing from {report}")
t = val("map", "E_RAYS_MS_MEDIAN", "edge.txt")
if f"{t:.2f}" not in text.split("Table VI")[1].split("## The link")[0]:
    sys.exit(f"Table VI misses {seq}'s (e) time {t:.2f}")
rays = val("map", "RAYS_PER_FRAME", "edge.txt")
if f"| {seq} | {rays:.1f} |" not in text:
    sys.exit(f"link table row of {seq} missing")
try:
    ms = val("map_start", "ATE_RMSE_m")
except SystemExit:
    sys.exit(0)  # a real run without the map-based start
locks = int(val("map_start", "LOCALISED", "edge.txt"))
doubted = int(val("map_start", "LOCKS_DOUBTED", "edge.txt"))
row = [l for l in text.splitlines() if l.startswith(f"| {seq} | seed1 |")]
if not row or f"| {locks} | {doubted} |" not in row[0] or not row[0].endswith(f"| {100 * ms:.2f} | {100 * m:.2f} | {ms / m:.2f} |"):
    sys.exit(f"per-run map-start row of {seq} missing (locks {locks}, doubted {doubted}, ATE {ms} vs {m})")
PY
}

if [[ -n $tree ]]; then
  [[ -f $tree/REPORT.md ]] || { echo "no report: $tree/REPORT.md"; exit 1; }
  n=0
  for d in "$tree"/runs/*/seed1; do
    seq=$(basename "$(dirname "$d")")
    expect_row "$tree/REPORT.md" "$tree" "$seq"
    n=$((n + 1))
  done
  [[ $n -gt 0 ]] || { echo "no seed-1 runs under $tree/runs"; fail=1; }
  [[ $fail -eq 0 ]] && echo "report of $tree: its $n sequence(s) filled from the run's result files"
  exit $fail
fi

for seed in 1 2; do
  make_tree "$tmp/t$seed" "$seed"
  "$py" "$root/scripts/lib/make_report.py" "$tmp/t$seed" --no-plots >/dev/null || { echo "make_report failed on tree $seed"; fail=1; }
  for seq in SeqA SeqB; do expect_row "$tmp/t$seed/REPORT.md" "$tmp/t$seed" "$seq"; done
  grep -q "edge_client SeqB fixed_0.02 seed$seed" "$tmp/t$seed/REPORT.md" || { echo "commands missing (tree $seed)"; fail=1; }
done
cmp -s "$tmp/t1/REPORT.md" "$tmp/t2/REPORT.md" && { echo "two different trees gave the same report"; fail=1; }
rm "$tmp/t1/runs/SeqA/seed1/map/eval.txt"
msg=$("$py" "$root/scripts/lib/make_report.py" "$tmp/t1" --no-plots 2>&1)
[[ $? -eq 1 && $msg == *"runs/SeqA/seed1/map/eval.txt"* ]] || { echo "a missing file was not an error naming it: $msg"; fail=1; }
[[ $fail -eq 0 ]] && echo "make_report: tables filled from the result files"
exit $fail
