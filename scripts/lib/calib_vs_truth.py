#!/usr/bin/python3
"""The calibration an edge_client run ended with against a generated sequence's truth.

Usage: scripts/lib/calib_vs_truth.py EDGE_REPORT SEQUENCE
  EDGE_REPORT  edge_client's stdout (its CALIB_* lines)
  SEQUENCE     the generated folder: mav0/camN/sensor.yaml (written) and
               sim0/true_calibration/ (camN/sensor.yaml, time_offset.yaml: the rendering rig)
Prints, for the written calibration and for the run's estimate, the error against the truth:
time offset (ms), each camera's camera-IMU rotation (deg) and translation (mm), focal length and
principal point (px, the larger of the two axes) as "KEY: written estimate" lines.
Exit 1 with a message naming the file for a missing or malformed input.
"""
import math
import sys

import numpy as np
import yaml


def fail(msg):
    print(f"calib_vs_truth.py: {msg}", file=sys.stderr)
    sys.exit(1)


def quat_to_rot(x, y, z, w):
    n = math.sqrt(x * x + y * y + z * z + w * w)
    x, y, z, w = x / n, y / n, z / n, w / n
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def angle_deg(Ra, Rb):
    c = (np.trace(Ra.T @ Rb) - 1.0) / 2.0
    return math.degrees(math.acos(max(-1.0, min(1.0, c))))


def read_sensor(path):
    try:
        with open(path) as f:
            doc = yaml.safe_load(f)
        T = np.array(doc["T_BS"]["data"], dtype=float).reshape(4, 4)
        return T, np.array(doc["intrinsics"], dtype=float)
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as e:
        fail(f"{path}: needs T_BS.data (16 numbers) and intrinsics ({e})")


def read_report(path):
    out = {}
    try:
        with open(path) as f:
            for line in f:
                if line.startswith("CALIB_") and ":" in line:
                    key, value = line.split(":", 1)
                    out[key] = [float(v) for v in value.split()]
    except (OSError, ValueError) as e:
        fail(f"{path}: {e}")
    for key in ("CALIB_TIME_OFFSET_MS", "CALIB_CAM0_T_B_C", "CALIB_CAM1_T_B_C",
                "CALIB_CAM0_INTRINSICS", "CALIB_CAM1_INTRINSICS"):
        if key not in out:
            fail(f"{path}: no {key} line (an edge_client report of this revision that initialised?)")
    return out


def main():
    if len(sys.argv) != 3:
        fail("usage: calib_vs_truth.py EDGE_REPORT SEQUENCE")
    report, seq = read_report(sys.argv[1]), sys.argv[2]
    truth_dir = f"{seq}/sim0/true_calibration"
    try:
        with open(f"{truth_dir}/time_offset.yaml") as f:
            td_true = float(yaml.safe_load(f)["time_offset_ms"])
    except (OSError, KeyError, TypeError, ValueError, yaml.YAMLError) as e:
        fail(f"{truth_dir}/time_offset.yaml: needs time_offset_ms ({e})")
    # The written time offset: the sensor.yaml files carry none, so 0 (the simulator's default).
    print(f"TIME_OFFSET_ERR_MS: {abs(td_true):.3f} {abs(report['CALIB_TIME_OFFSET_MS'][0] - td_true):.3f}")
    for c in (0, 1):
        T_w, K_w = read_sensor(f"{seq}/mav0/cam{c}/sensor.yaml")
        T_t, K_t = read_sensor(f"{truth_dir}/cam{c}/sensor.yaml")
        x, y, z, qx, qy, qz, qw = report[f"CALIB_CAM{c}_T_B_C"]
        R_e, p_e = quat_to_rot(qx, qy, qz, qw), np.array([x, y, z])
        K_e = np.array(report[f"CALIB_CAM{c}_INTRINSICS"][:4])
        print(f"CAM{c}_ROT_ERR_DEG: {angle_deg(T_w[:3, :3], T_t[:3, :3]):.4f} {angle_deg(R_e, T_t[:3, :3]):.4f}")
        print(f"CAM{c}_TRANS_ERR_MM: {1e3 * np.linalg.norm(T_w[:3, 3] - T_t[:3, 3]):.3f} "
              f"{1e3 * np.linalg.norm(p_e - T_t[:3, 3]):.3f}")
        print(f"CAM{c}_FOCAL_ERR_PX: {np.abs(K_w[:2] - K_t[:2]).max():.3f} {np.abs(K_e[:2] - K_t[:2]).max():.3f}")
        print(f"CAM{c}_PP_ERR_PX: {np.abs(K_w[2:4] - K_t[2:4]).max():.3f} {np.abs(K_e[2:4] - K_t[2:4]).max():.3f}")


if __name__ == "__main__":
    main()
