#!/usr/bin/env python3
"""Writes REPORT.md (and its PNG figures) from the result files of scripts/run_experiments.sh.

Usage: make_report.py RESULTS_DIR [--no-plots]

RESULTS_DIR layout (written by run_experiments.sh; every number in the report comes from it):
  meta.txt                         KEY: value lines (date, git revision, versions, mode, seeds)
  runs/<sequence>/seed<N>/<variant>/edge.txt     edge_client's KEY: value report
  runs/<sequence>/seed<N>/<variant>/eval.txt     evaluate_trajectory's KEY: value report
  runs/<sequence>/seed<N>/<variant>/command.txt  the exact command of the run
  runs/<sequence>/seed<N>/groundtruth.csv        path of the sequence's ground truth (one line)
  link/<name>.txt                  tables printed by the link experiments (optional)
Variants: plain, map, gt, fixed_<metres> (the paper's start: ground truth + 2 cm) and map_start
(the map-based start: no ground truth, the cloud's localisation; alignment.txt holds the error
of the pose where the cloud placed the edge). A missing file is an error naming it.
"""
import os
import re
import statistics
import sys


class ReportError(Exception):
    pass


def read_keys(path, as_text=False):
    """KEY: value lines of a report file, values as float where they parse (unless as_text)."""
    if not os.path.isfile(path):
        raise ReportError(f"missing result file {path} (rerun scripts/run_experiments.sh)")
    out = {}
    with open(path) as f:
        for line in f:
            m = re.match(r"^([A-Z][A-Za-z0-9_]*): (\S+)\s*$", line)
            if m and as_text:
                out[m.group(1)] = m.group(2)
            elif m:
                try:
                    out[m.group(1)] = float(m.group(2))
                except ValueError:
                    out[m.group(1)] = m.group(2)
    return out


def need(keys, key, path):
    if key not in keys:
        raise ReportError(f"{path}: no '{key}:' line (incomplete run?)")
    return keys[key]


def load_runs(root):
    """{sequence: {variant: [run dict per seed]}} with the edge and eval figures."""
    runs_dir = os.path.join(root, "runs")
    if not os.path.isdir(runs_dir):
        raise ReportError(f"missing folder {runs_dir} (rerun scripts/run_experiments.sh)")
    runs = {}
    for seq in sorted(os.listdir(runs_dir)):
        for seed_dir in sorted(os.listdir(os.path.join(runs_dir, seq))):
            base = os.path.join(runs_dir, seq, seed_dir)
            if not os.path.isdir(base):
                continue
            for variant in sorted(os.listdir(base)):
                d = os.path.join(base, variant)
                if not os.path.isdir(d):
                    continue
                edge_path, eval_path = os.path.join(d, "edge.txt"), os.path.join(d, "eval.txt")
                cmd_path = os.path.join(d, "command.txt")
                if not os.path.isfile(cmd_path):
                    raise ReportError(f"missing result file {cmd_path}")
                run = {"seed": seed_dir, "dir": d, "edge": read_keys(edge_path), "eval": read_keys(eval_path),
                       "edge_path": edge_path, "eval_path": eval_path, "command": open(cmd_path).read().strip()}
                align_path = os.path.join(d, "alignment.txt")
                run["alignment"] = read_keys(align_path) if os.path.isfile(align_path) else {}
                runs.setdefault(seq, {}).setdefault(variant, []).append(run)
    if not runs:
        raise ReportError(f"no runs under {runs_dir}")
    return runs


def mean_of(runs, source, key):
    return statistics.mean(need(r[source], key, r[source + "_path"]) for r in runs)


def cm(x):
    return f"{100.0 * x:.2f}"


def ratio(a, b):
    return f"{a / b:.2f}" if b > 0 else "n/a"


def table(header, rows):
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in row) + " |" for row in rows]
    return "\n".join(out) + "\n"


def accuracy_tables(runs):
    rows2, rows3, rows45 = [], [], []
    for seq, variants in runs.items():
        if "plain" in variants and "map" in variants:
            p, m = variants["plain"], variants["map"]
            pr, mr = mean_of(p, "eval", "ATE_RMSE_m"), mean_of(m, "eval", "ATE_RMSE_m")
            ps, ms = mean_of(p, "eval", "ATE_RMSE_SE3_m"), mean_of(m, "eval", "ATE_RMSE_SE3_m")
            rows2.append([seq, len(m), cm(pr), cm(mr), ratio(mr, pr), cm(ps), cm(ms), ratio(ms, ps)])
        if "map" in variants and "gt" in variants:
            mr, gr = mean_of(variants["map"], "eval", "ATE_RMSE_m"), mean_of(variants["gt"], "eval", "ATE_RMSE_m")
            rows3.append([seq, cm(mr), cm(gr), ratio(gr, mr)])
        fixed = sorted((v for v in variants if v.startswith("fixed_")), key=lambda v: float(v[6:]))
        if fixed and "map" in variants:
            row = [seq, cm(mean_of(variants["map"], "eval", "ATE_RMSE_m"))]
            row += [cm(mean_of(variants[v], "eval", "ATE_RMSE_m")) for v in fixed]
            rows45.append((tuple(v[6:] for v in fixed), row))
    text = "## Accuracy with and without the map (Table II-like)\n\n"
    text += ("From the paper's start (the ground truth plus 2 cm at initialisation, the ablation gt_noisy); "
             "the map-based start (no ground truth: the cloud's localisation) is in its own table below.\n\n")
    text += "ATE RMSE in cm, mean over the seeds; unaligned (the map frame) and SE(3)-aligned.\n\n"
    text += table(["sequence", "seeds", "plain", "with map", "ratio", "plain SE3", "map SE3", "ratio SE3"], rows2)
    text += localisation_table(runs)
    text += "\n## With the map vs ground-truth query poses (Table III-like)\n\n"
    text += table(["sequence", "w/ map", "w/ GT queries", "ratio"], rows3)
    text += "\n## Fixed resolution vs multi-resolution (Tables IV/V-like)\n\nATE RMSE in cm, unaligned.\n\n"
    for levels in sorted({lv for lv, _ in rows45}):
        text += table(["sequence", "multi-resolution"] + [f"fixed {lv} m" for lv in levels],
                      [row for lv, row in rows45 if lv == levels])
    return text


def localisation_table(runs):
    """The map-based start next to the paper's: localised runs, time, alignment error, ATE."""
    rows = []
    for seq, variants in runs.items():
        if "map_start" not in variants:
            continue
        ms = variants["map_start"]
        done = [r for r in ms if float(r["edge"].get("LOCALISED", "0")) >= 1]
        after = [float(r["edge"]["LOCALISED_AFTER_S"]) for r in done]
        err_m = [float(r["alignment"]["POSE_ERROR_AT_M"]) for r in done if r["alignment"]]
        err_deg = [float(r["alignment"]["POSE_ERROR_AT_DEG"]) for r in done if r["alignment"]]
        start = mean_of(ms, "eval", "ATE_RMSE_m") if len(done) == len(ms) else None
        paper = mean_of(variants["map"], "eval", "ATE_RMSE_m") if "map" in variants else None
        rows.append([seq, f"{len(done)}/{len(ms)}",
                     f"{statistics.mean(after):.1f}" if after else "n/a",
                     cm(statistics.median(err_m)) if err_m else "n/a",
                     f"{statistics.median(err_deg):.2f}" if err_deg else "n/a",
                     cm(start) if start is not None else "n/a (not all localised)",
                     cm(paper) if paper is not None else "n/a",
                     ratio(start, paper) if start is not None and paper else "n/a"])
    if not rows:
        return ""
    text = "\n## The map-based start (no ground truth) next to the paper's start\n\n"
    text += ("map_start: edge_client in real time with alignment.source map; the cloud's localisation service "
             "places it. Localised runs, time from initialisation to the accepted answer (s, mean), the error of "
             "the pose at that frame against the truth (cm and deg, median), unaligned ATE (cm, mean; the poses "
             "before the answer mapped by it) against the paper's start (with map, gt_noisy).\n\n")
    text += table(["sequence", "localised", "after s", "alignment cm", "alignment deg", "ATE map start",
                   "ATE paper start", "ratio"], rows)
    return text + localisation_runs_table(runs)


def count(keys, key):
    return str(int(float(keys[key]))) if key in keys else "n/a"


def localisation_runs_table(runs):
    """Per seed: the map-based start against the paper's start of the same seed, with the locks
    (a doubted lock is searched again: more than one lock per run), the pose fixes applied and
    refused, and how many runs stay within 1.1 x the paper's start."""
    rows, within, total = [], 0, 0
    for seq, variants in runs.items():
        paper = {r["seed"]: r for r in variants.get("map", [])}
        for r in variants.get("map_start", []):
            e, a = r["edge"], r["alignment"]
            start = float(need(r["eval"], "ATE_RMSE_m", r["eval_path"]))
            p = paper.get(r["seed"])
            gt = float(need(p["eval"], "ATE_RMSE_m", p["eval_path"])) if p else None
            total += gt is not None
            within += gt is not None and start <= 1.1 * gt
            rows.append([seq, r["seed"], e.get("LOCALISED_AFTER_S", "n/a") if float(e.get("LOCALISED", "0")) >= 1
                         else "not localised",
                         cm(float(a["POSE_ERROR_AT_M"])) if a else "n/a",
                         f"{float(a['POSE_ERROR_AT_DEG']):.2f}" if a else "n/a",
                         count(e, "LOCALISED"), count(e, "LOCKS_DOUBTED"),
                         f"{count(e, 'LOCALISATION_FIXES')} / {count(e, 'LOCALISATION_FIXES_REFUSED')}",
                         cm(start), cm(gt) if gt is not None else "n/a",
                         ratio(start, gt) if gt else "n/a"])
    if not rows:
        return ""
    text = ("\nPer run (alignment: the error at the first lock; locks: accepted answers, a doubted lock is searched "
            f"again; fixes: pose fixes applied / refused by the edge's gate). Within 1.1 x the paper's start: "
            f"**{within}/{total}**.\n\n")
    return text + table(["sequence", "seed", "localised after s", "alignment cm", "alignment deg", "locks",
                         "doubted", "fixes", "ATE map start", "ATE paper start", "ratio"], rows)


TIMING = [("A_IMAGE", "(a) image processing"), ("B_TRACKING", "(b) extraction + tracking"),
          ("C_UPDATE", "(c) state update"), ("D_SELECTION", "(d) map-point selection"),
          ("E_RAYS", "(e) ray indexing incl. round trip"), ("FRAME", "total")]


def timing_table(runs):
    rows = []
    for seq, variants in runs.items():
        if "map" not in variants:
            continue
        m = variants["map"]
        rows.append([seq] + [f"{mean_of(m, 'edge', key + '_MS_MEDIAN'):.2f}" for key, _ in TIMING]
                    + [f"{mean_of(m, 'edge', 'FRAME_MS_P95'):.2f}", f"{mean_of(m, 'edge', 'FRAME_INTERVAL_MS'):.1f}"])
    text = "\n## Per-frame time (Table VI-like)\n\nMedian ms per frame with the map, single thread, "
    text += "this machine; mean over the seeds.\n\n"
    return text + table(["sequence"] + [label for _, label in TIMING] + ["total p95", "frame interval"], rows)


def link_section(root, runs):
    rows = []
    for seq, variants in runs.items():
        if "map" not in variants:
            continue
        m = variants["map"]
        rows.append([seq, f"{mean_of(m, 'edge', 'RAYS_PER_FRAME'):.1f}",
                     f"{mean_of(m, 'edge', 'PAYLOAD_UP_BYTES_PER_FRAME'):.0f}",
                     f"{mean_of(m, 'edge', 'PAYLOAD_DOWN_BYTES_PER_FRAME'):.0f}",
                     f"{mean_of(m, 'edge', 'RTT_MS_MEDIAN'):.3f}", f"{mean_of(m, 'edge', 'RTT_MS_P95'):.3f}",
                     f"{mean_of(m, 'edge', 'MAP_TIMEOUTS'):.0f}"])
    text = "\n## The link\n\nedge_client and cloud_server over Fast DDS on loopback (application payload).\n\n"
    text += table(["sequence", "rays/frame", "bytes up/frame", "bytes down/frame", "RTT p50 ms", "RTT p95 ms",
                   "timeouts"], rows)
    link_dir = os.path.join(root, "link")
    if os.path.isdir(link_dir):
        for name in sorted(os.listdir(link_dir)):
            with open(os.path.join(link_dir, name)) as f:
                text += f"\n### {name[:-4] if name.endswith('.txt') else name}\n\n```\n{f.read().rstrip()}\n```\n"
    else:
        text += "\nTwo-host and throttled runs: not run (they need root, and --quick leaves them out).\n"
    return text


def plots(root, runs):
    """Trajectory/error plots for up to two sequences (their last seed folder) and the timing breakdown; their names."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    import numpy as np

    here = os.path.dirname(os.path.abspath(__file__))
    sys.path.insert(0, here)
    import plot_trajectories

    names = []
    for seq in list(runs)[:2]:
        v = runs[seq]
        if "plain" not in v or "map" not in v:
            continue
        gt_file = os.path.join(os.path.dirname(v["map"][-1]["dir"]), "groundtruth.csv")
        gt = open(gt_file).read().strip() if os.path.isfile(gt_file) else ""
        if not os.path.isfile(gt):
            raise ReportError(f"{gt_file}: does not name an existing ground-truth file")
        name = f"trajectory_{seq}.png"
        plot_trajectories.main(["", os.path.join(root, name), gt,
                                "with map=" + os.path.join(v["map"][-1]["dir"], "trajectory.txt"),
                                "plain VIO=" + os.path.join(v["plain"][-1]["dir"], "trajectory.txt")])
        names.append(name)
    seqs = [s for s in runs if "map" in runs[s]]
    if seqs:
        fig, ax = plt.subplots(figsize=(7, 3.5))
        bottom = np.zeros(len(seqs))
        for key, label in TIMING[:-1]:
            vals = np.array([mean_of(runs[s]["map"], "edge", key + "_MS_MEDIAN") for s in seqs])
            ax.bar(seqs, vals, bottom=bottom, label=label)
            bottom += vals
        ax.set_ylabel("median ms per frame")
        ax.set_title("per-frame time with the map")
        ax.legend(fontsize=7)
        fig.tight_layout()
        fig.savefig(os.path.join(root, "timing.png"), dpi=90)
        names.append("timing.png")
    return names


def reproduce_section(root, runs):
    meta = read_keys(os.path.join(root, "meta.txt"), as_text=True)
    text = "\n## How these numbers were made\n\n"
    text += table(["key", "value"], [[k, v] for k, v in meta.items()])
    text += "\nEvery run's command (each run folder also keeps its edge_client report and evaluation):\n\n```\n"
    for seq, variants in runs.items():
        for variant, rs in variants.items():
            for r in rs:
                text += r["command"] + "\n"
    return text + "```\n"


def main(argv):
    if len(argv) < 2:
        sys.exit(__doc__)
    root = argv[1]
    try:
        runs = load_runs(root)
        text = "# MR-Voxel-SVIO on generated data: the paper's evaluation\n\n"
        text += "Written by `scripts/lib/make_report.py` from the result files in this folder.\n\n"
        text += accuracy_tables(runs) + timing_table(runs) + link_section(root, runs)
        if "--no-plots" not in argv:
            figures = plots(root, runs)
            text += "\n## Figures\n\nTrajectories: the last seed folder of each sequence.\n\n"
            text += "".join(f"![{f}]({f})\n\n" for f in figures)
        text += reproduce_section(root, runs)
    except ReportError as e:
        print(f"make_report.py: error: {e}", file=sys.stderr)
        return 1
    with open(os.path.join(root, "REPORT.md"), "w") as f:
        f.write(text)
    print(os.path.join(root, "REPORT.md"))
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv))
