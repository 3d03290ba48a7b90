#!/usr/bin/env bash
# scripts/lib/replay_summary.py on hand-made REPLAY lines: the counts, and the edge's rule as
# map_localiser.cpp has it: two agreeing ok answers from independent submaps lock; an ok answer
# and an ambiguous one's best guess lock only with guesses_confirm; a guess of another pose, or
# a search stopped without hypotheses, does not; a lock on a wrong answer counts as wrong.
set -uo pipefail
root=$1
dir=$(mktemp -d)
trap 'rm -rf "$dir"' EXIT
line() {  # clip k status ambiguity error_m error_deg ms hypotheses tx yaw detail
  printf "REPLAY /d/T/%s/req_%s.txt status '%s' ambiguity %s fitness 0.80 error %s m %s deg %s ms (%s) " \
    "$1" "$2" "$3" "$4" "$5" "$6" "$7" "${11}"
  printf "error_xyz 0 0 0 truth_fitness 0.8 from_truth 0.01 m fitness 0.8 hypotheses %s T_m_o %s 0 0 yaw %s anchor_o 0 0 0\n" \
    "$8" "$9" "${10}"
}
sd="fitness 0.80, rmse 0.02 m, ambiguity 0.30, sd 0.010 m / 0.20 deg"
{
  line two_ok 1 ok 0.30 0.01 0.1 200 3 1.0 0.5 "$sd"
  line two_ok 2 ok 0.30 0.01 0.1 200 3 1.0 0.5 "$sd"
  line ok_guess 1 ok 0.30 0.01 0.1 200 3 1.0 0.5 "$sd"
  line ok_guess 2 ambiguous 0.90 0.01 0.1 200 6 1.0 0.5 "another pose"
  line guess_other 1 ok 0.30 0.01 0.1 200 3 1.0 0.5 "$sd"
  line guess_other 2 ambiguous 0.90 4.00 90 200 6 5.0 2.07 "another pose"
  line stopped 1 ok 0.30 0.01 0.1 200 3 1.0 0.5 "$sd"
  line stopped 2 ambiguous 1.00 0.01 0.1 900 0 1.0 0.5 "the search stopped"
  line wrong 1 ok 0.30 3.00 90 200 3 4.0 2.07 "$sd"
  line wrong 2 ok 0.30 3.00 90 200 3 4.0 2.07 "$sd"
} >"$dir/replay.txt"
out=$(python3 "$root/scripts/lib/replay_summary.py" "$dir/replay.txt") || { echo "replay_summary.py failed"; exit 1; }
echo "$out"
fail=0
expect() { grep -qF -- "$1" <<<"$out" || { echo "missing: $1"; fail=1; }; }
expect "requests 10 in 5 clips: ok 7 (wrong 2), ambiguous 3"
expect "guesses_confirm false: within 5 s 1/5, at all 1, wrong locks 1; later or never: T/guess_other -, T/ok_guess -, T/stopped -, T/wrong WRONG"
expect "guesses_confirm true: within 5 s 2/5, at all 2, wrong locks 1; later or never: T/guess_other -, T/stopped -, T/wrong WRONG"
"$root/scripts/lib/replay_summary.py" "$dir/none.txt" >/dev/null 2>&1 && { echo "a missing file was not refused"; fail=1; }
: >"$dir/empty.txt"
"$root/scripts/lib/replay_summary.py" "$dir/empty.txt" >/dev/null 2>&1 && { echo "a file without REPLAY lines was not refused"; fail=1; }
exit $fail
