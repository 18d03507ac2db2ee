#!/usr/bin/env python3
"""Loop closure end to end: a rendered garage lap and a bit (parking_lot, no traffic, 37 s; the
lap takes 33 s) run with loop_closure 1 and --save-map. At least one loop, no false loop (a loop edge whose
relative pose disagrees with the ground truth by more than 0.3 m or 3 deg), trajectory_loop.tum
with a pose per odometry pose, loops.csv, stats.json and the saved map agreeing. Debian's python3 with numpy.

Usage: loop_check.py IDYVINS_BINARY WORK_DIR [--keep]"""
import bisect
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def yaw(R):
    return math.atan2(R[1, 0], R[0, 0])


def rotation(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def loop_errors(dataset, loops_csv):
    """Per loop: translation (m) and yaw (rad) error of its relative pose against the ground truth."""
    gt = np.loadtxt(os.path.join(dataset, "mav0", "state_groundtruth_estimate0", "data.csv"), delimiter=",",
                    comments="#")
    ts = gt[:, 0].astype(np.int64)

    def pose(t):
        r = gt[min(bisect.bisect_left(ts, t), len(ts) - 1)]
        return r[1:4], rotation(*r[4:8])
    errors = []
    for line in open(loops_csv):
        if line.startswith("#"):
            continue
        f = line.strip().split(",")
        p0, R0 = pose(int(f[0]))
        p1, R1 = pose(int(f[1]))
        d_t = np.linalg.norm(R0.T @ (p1 - p0) - np.array([float(v) for v in f[7:10]]))
        d_yaw = abs((yaw(R1) - yaw(R0) - float(f[10]) + math.pi) % (2 * math.pi) - math.pi)
        errors.append((d_t, d_yaw))
    return errors


def main(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    seq, out = os.path.join(work, "seq"), os.path.join(work, "out")
    r = subprocess.run([idy, "simulate", "--scene", "parking_lot", "--level", "none", "--seed", "1", "--duration", "37",
                        "--out", seq], capture_output=True, text=True)
    check(r.returncode == 0, "simulate (%s)" % r.stderr.strip()[-200:])
    cfg = os.path.join(seq, "config", "sim_stereo_imu_config.yaml")
    text = open(cfg).read()
    check("loop_closure: 0" in text, "the simulator's config has loop_closure off by default")
    open(cfg, "w").write(text.replace("loop_closure: 0", "loop_closure: 1"))
    saved = os.path.join(work, "map")
    r = subprocess.run([idy, "run", "-c", cfg, "-d", seq, "-o", out, "--save-map", saved], capture_output=True, text=True)
    check(r.returncode == 0, "run completes (%s)" % r.stderr.strip()[-200:])
    s = json.load(open(os.path.join(out, "stats.json")))["summary"]
    loop = s["loop_closure"]
    errors = loop_errors(seq, os.path.join(out, "loops.csv"))
    check(loop["loops"] >= 1 and len(errors) == loop["loops"],
          "loops closed: %d (loops.csv %d), keyframes %d" % (loop["loops"], len(errors), loop["keyframes"]))
    false = [e for e in errors if e[0] > 0.3 or e[1] > math.radians(3)]
    worst = (max(e[0] for e in errors), math.degrees(max(e[1] for e in errors))) if errors else (0, 0)
    check(not false, "no false loop (worst %.3f m, %.2f deg)" % worst)
    odo = [l for l in open(os.path.join(out, "trajectory.tum")) if not l.startswith("#")]
    cor = [l for l in open(os.path.join(out, "trajectory_loop.tum")) if not l.startswith("#")]
    check(len(odo) == len(cor) and len(odo) > 600, "trajectory_loop.tum: a pose per odometry pose (%d, %d)"
          % (len(cor), len(odo)))
    check("ate_rmse_m" in loop, "ATE of the loop trajectory in stats.json")
    header = json.load(open(os.path.join(saved, "map.json")))
    check(header["format"] == "idyvins-map" and header["keyframes"] == loop["keyframes"]
          and header["loops"] == loop["loops"] and os.path.getsize(os.path.join(saved, "keyframes.bin")) > 1000,
          "--save-map wrote the database and the pose graph (%d keyframes, %d loops)" % (header["keyframes"],
                                                                                        header["loops"]))
    print("odometry ATE %.4f m, with loops %.4f m; detection %.1f ms per keyframe, pose graph %.1f ms per solve"
          % (s["ate_rmse_m"], loop.get("ate_rmse_m", float("nan")), loop["mean_detect_ms_per_keyframe"],
             loop["mean_graph_ms_per_solve"]))
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
