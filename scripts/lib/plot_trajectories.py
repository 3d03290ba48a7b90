#!/usr/bin/env python3
"""Top view (x-y) of estimated trajectories against the ground truth, and their position
error over time, as one PNG.

Usage: plot_trajectories.py OUT.png GROUNDTRUTH.csv LABEL=TRAJ.txt [LABEL=TRAJ.txt ...]
GROUNDTRUTH: EuRoC state_groundtruth_estimate0/data.csv; TRAJ: TUM (t x y z qx qy qz qw).
"""
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt  # noqa: E402
import numpy as np  # noqa: E402


def main(argv):
    if len(argv) < 4:
        sys.exit(__doc__)
    out, gt_path, runs = argv[1], argv[2], argv[3:]
    gt = np.loadtxt(gt_path, delimiter=",", comments="#", usecols=(0, 1, 2, 3))
    t_gt = gt[:, 0] * 1e-9
    fig, (top, err) = plt.subplots(1, 2, figsize=(11, 4.5))
    top.plot(gt[:, 1], gt[:, 2], "k-", lw=1.5, label="ground truth")
    for run in runs:
        label, path = run.split("=", 1)
        est = np.atleast_2d(np.loadtxt(path))
        t = est[:, 0]
        inside = (t >= t_gt[0]) & (t <= t_gt[-1])
        est, t = est[inside], t[inside]
        ref = np.stack([np.interp(t, t_gt, gt[:, i]) for i in (1, 2, 3)], axis=1)
        e = np.linalg.norm(est[:, 1:4] - ref, axis=1)
        rmse = float(np.sqrt(np.mean(e**2))) if len(e) else float("nan")
        top.plot(est[:, 1], est[:, 2], lw=1.0, label=f"{label} (ATE {rmse * 100:.1f} cm)")
        err.plot(t - t_gt[0], e * 100, lw=1.0, label=label)
    top.set_xlabel("x [m]")
    top.set_ylabel("y [m]")
    top.set_aspect("equal", adjustable="datalim")
    top.set_title("top view (map frame, no alignment)")
    top.legend(fontsize=8)
    err.set_xlabel("time [s]")
    err.set_ylabel("position error [cm]")
    err.set_title("error over time")
    err.grid(alpha=0.3)
    err.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(out, dpi=90)


if __name__ == "__main__":
    main(sys.argv)
