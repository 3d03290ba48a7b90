#!/usr/bin/env python3
"""Summarises `localise_probe --replay` output (REPLAY lines) of many clips: the cloud's answers
(ok, wrong, ambiguous, registration time) and what the edge's acceptance rule
(edge_client/estimator/src/map_localiser.cpp) would make of them, with and without
`guesses_confirm`: per clip when it would localise and whether the lock would be wrong.

The edge is simulated from the dumped requests in their order: the first request 1 s after
initialisation, the next one 1 s later or when the reply came (registration time), the submap's
time span 1.5 s, growing 1.5x after a refused answer up to 6 s and back to 1.5 s after an ok
one; two answers are independent when their spans share at most half the shorter one; they
agree when they place the later anchor within chi-square(4, 99 %) of their sd (from the ok
answer's detail; 2 cm / 0.3 deg for an ambiguous one) plus 5 cm / 0.5 deg. Approximate (the
real edge's requests depend on its own timing): a tuning aid, not a result; results come from
scripts/localisation_experiment.sh.

Usage: replay_summary.py REPLAY_TXT [--cost-ms MS]   (MS: a fixed registration time instead
of the replayed one)
"""
import argparse
import math
import re
import statistics

LINE = re.compile(
    r"REPLAY (\S+)/req_(\d+)\.txt status '([^']+)' ambiguity (\S+) fitness (\S+) error (\S+) m (\S+) deg "
    r"(\S+) ms \((.*)\) error_xyz .* hypotheses (\d+) T_m_o (\S+) (\S+) (\S+) yaw (\S+) anchor_o (\S+) (\S+) (\S+)")
SD = re.compile(r"sd (\S+) m / (\S+) deg")
EDGE_MAX_AMBIGUITY = 0.6  # config/euroc.yaml estimator.localisation.max_ambiguity


def load(path):
    clips = {}
    try:
        lines = open(path).read().splitlines()
    except OSError as e:
        raise SystemExit(f"replay_summary.py: cannot read {path}: {e.strerror} (give localise_probe --replay output)")
    for line in lines:
        m = LINE.match(line)
        if not m:
            continue
        g = m.groups()
        sd = SD.search(g[8])
        clips.setdefault(g[0], []).append(dict(
            k=int(g[1]), status=g[2], ambiguity=float(g[3]), error_m=float(g[5]), error_deg=float(g[6]),
            ms=float(g[7]), hypotheses=int(g[9]), t=[float(x) for x in g[10:13]], yaw=float(g[13]),
            anchor=[float(x) for x in g[14:17]], sd_m=float(sd.group(1)) if sd else 0.02,
            sd_deg=float(sd.group(2)) if sd else 0.3))
    for answers in clips.values():
        answers.sort(key=lambda a: a["k"])
    return clips


def wrong(a):
    return a["error_m"] > 0.1 or a["error_deg"] > 2.0


def place(a, p):
    c, s = math.cos(a["yaw"]), math.sin(a["yaw"])
    return [c * p[0] - s * p[1] + a["t"][0], s * p[0] + c * p[1] + a["t"][1], p[2] + a["t"][2]]


def agree(earlier, later):
    d2 = sum((x - y) ** 2 for x, y in zip(place(earlier, later["anchor"]), place(later, later["anchor"])))
    dyaw = math.remainder(earlier["yaw"] - later["yaw"], 2 * math.pi)
    var_m = earlier["sd_m"] ** 2 + later["sd_m"] ** 2 + 0.05 ** 2
    var_yaw = math.radians(earlier["sd_deg"]) ** 2 + math.radians(later["sd_deg"]) ** 2 + math.radians(0.5) ** 2
    return d2 / var_m + dyaw * dyaw / var_yaw <= 13.277


def independent(a, b):
    overlap = min(a["at"], b["at"]) - max(a["at"] - a["span"], b["at"] - b["span"])
    return overlap <= 0.5 * min(a["span"], b["span"])


def simulate(answers, guesses_confirm, cost_ms=None):
    """(time after initialisation, accepted answer) or (None, None)."""
    t, span = 1.0, 1.5
    candidates, guesses = [], []
    for answer in answers:
        a = dict(answer, at=t, span=span)
        reply = t + (a["ms"] if cost_ms is None else cost_ms) / 1000.0
        if a["status"] == "ok" and a["ambiguity"] <= EDGE_MAX_AMBIGUITY:
            if candidates and not agree(candidates[-1], a):
                candidates, span = [a], 1.5
            elif not candidates or independent(candidates[-1], a):
                candidates.append(a)
                span = 1.5
                if len(candidates) >= 2:
                    return reply, a
                if guesses_confirm and any(independent(g, a) and agree(g, a) for g in guesses[-16:]):
                    return reply, a
        else:
            guess = a["status"] == "ambiguous" and a["hypotheses"] > 0
            if guesses_confirm and guess and candidates and independent(candidates[-1], a) and \
                    agree(candidates[-1], a):
                return reply, candidates[-1]
            if guess:
                guesses.append(a)
            span = min(6.0, 1.5 * span)
        t = max(t + 1.0, reply)
    return None, None


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("replay")
    ap.add_argument("--cost-ms", type=float)
    args = ap.parse_args()
    clips = load(args.replay)
    answers = [a for c in clips.values() for a in c]
    if not answers:
        raise SystemExit(f"replay_summary.py: no REPLAY lines in {args.replay} (localise_probe --replay output)")
    ms = sorted(a["ms"] for a in answers)
    ok = [a for a in answers if a["status"] == "ok"]
    print(f"requests {len(answers)} in {len(clips)} clips: ok {len(ok)} (wrong {sum(map(wrong, ok))}), "
          f"ambiguous {sum(a['status'] == 'ambiguous' for a in answers)}; registration median "
          f"{statistics.median(ms):.0f} ms, p95 {ms[min(len(ms) - 1, int(0.95 * len(ms)))]:.0f} ms")
    for guesses_confirm in (False, True):
        within5 = locked = wrong_locks = 0
        late = []
        for clip, seq in sorted(clips.items()):
            t, a = simulate(seq, guesses_confirm, args.cost_ms)
            name = "/".join(clip.split("/")[-2:])
            if a is None:
                late.append(f"{name} -")
            elif wrong(a):
                wrong_locks += 1
                late.append(f"{name} WRONG")
            else:
                locked += 1
                within5 += t <= 5.0
                if t > 5.0:
                    late.append(f"{name} {t:.1f} s")
        print(f"edge (simulated), guesses_confirm {str(guesses_confirm).lower()}: within 5 s {within5}/{len(clips)}, "
              f"at all {locked}, wrong locks {wrong_locks}; later or never: {', '.join(late) or 'none'}")


if __name__ == "__main__":
    main()
