#!/usr/bin/env python3
"""Loop closure end to end: a rendered garage lap and a bit (parking_lot, no traffic, 37 s; the
lap takes 33 s) run with loop_closure 1 and --save-map. At least one loop, no false loop (a loop edge whose
relative pose disagrees with the ground truth by more than 0.3 m or 3 deg), trajectory_loop.tum
with a pose per odometry pose, loops.csv, stats.json and the saved map agreeing.
Then relocalization: another run through the same garage (--traffic-seed 2: another start and
noise, 20 s) with --load-map relocalizes, its loops to the map are true, its map poses agree with
the ground truth through the first run's alignment, --save-map extends the map; --localization-only
closes loops to the map only; a map from another camera and option misuse are one clear error.
Debian's python3 with numpy.

Usage: loop_check.py IDYVINS_BINARY WORK_DIR [--keep]"""
import json
import math
import os
import shutil
import subprocess
import sys

import numpy as np

sys.path.insert(0, os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "bench"))
from loops_eval import ground_truth, loop_errors, read_tum, umeyama_se3  # noqa: E402  (the benchmark's own measures)

failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def main(idy, work):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    seq, out = os.path.join(work, "seq"), os.path.join(work, "out")
    r = subprocess.run([idy, "simulate", "--scene", "parking_lot", "--level", "none", "--seed", "1", "--duration", "37",
                        "--out", seq], capture_output=True, text=True)
    check(r.returncode == 0, "simulate (%s)" % r.stderr.strip()[-200:])
    cfg = os.path.join(seq, "config", "sim_stereo_imu_config.yaml")
    text = open(cfg).read()
    check("loop_closure:" not in text, "the simulator's config leaves loop_closure at its default (off)")
    open(cfg, "w").write(text + "loop_closure: 1\n")
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
    relocalization(idy, work, seq, cfg, out, saved)
    return 1 if failures else 0


def relocalization(idy, work, seq_a, cfg, out_a, saved):
    seq_b, out_b, saved_b = (os.path.join(work, n) for n in ("seq_b", "out_b", "map_b"))
    r = subprocess.run([idy, "simulate", "--scene", "parking_lot", "--level", "none", "--seed", "1", "--traffic-seed",
                        "2", "--duration", "20", "--out", seq_b], capture_output=True, text=True)
    check(r.returncode == 0, "simulate the second run (%s)" % r.stderr.strip()[-200:])
    r = subprocess.run([idy, "run", "-c", cfg, "-d", seq_b, "-o", out_b, "--load-map", saved, "--save-map", saved_b],
                       capture_output=True, text=True)
    check(r.returncode == 0, "run --load-map completes (%s)" % r.stderr.strip()[-200:])
    loop = json.load(open(os.path.join(out_b, "stats.json")))["summary"]["loop_closure"]
    m = loop["map"]
    header_a = json.load(open(os.path.join(saved, "map.json")))
    check(m["loaded_keyframes"] == header_a["keyframes"] and m["relocalized"] and m["loops_to_map"] >= 2,
          "relocalized in the loaded map: %d keyframes loaded, %d loops to it, first at %.1f s" %
          (m["loaded_keyframes"], m["loops_to_map"], (m["first_relocalization_t_ns"] - 1700000000000000000) / 1e9))
    errors = loop_errors(seq_b, os.path.join(out_b, "loops.csv"), map_dataset=seq_a)
    worst = (max(e[0] for e in errors), math.degrees(max(e[1] for e in errors))) if errors else (0, 0)
    check(errors and all(e[0] <= 0.3 and e[1] <= math.radians(3) for e in errors),
          "no wrong relocalization or false loop (%d loops, worst %.3f m, %.2f deg)" % (len(errors), *worst))
    # Map poses against the ground truth through the first run's alignment (no re-alignment).
    gt_a, gt_b = ground_truth(seq_a), ground_truth(seq_b)
    ta, pa = read_tum(os.path.join(out_a, "trajectory_loop.tum"))
    R, t = umeyama_se3(pa, np.array([gt_a(x)[0] for x in ta]))
    tb, pb = read_tum(os.path.join(out_b, "trajectory_loop.tum"))
    after = tb >= m["first_relocalization_t_ns"]
    err = np.linalg.norm((pb[after] @ R.T + t) - np.array([gt_b(x)[0] for x in tb[after]]), axis=1)
    check(after.sum() > 100 and np.sqrt((err ** 2).mean()) < 0.1,
          "map poses after relocalization: %d, RMSE %.3f m in the map's ground-truth alignment" %
          (after.sum(), np.sqrt((err ** 2).mean())))
    header_b = json.load(open(os.path.join(saved_b, "map.json")))
    check(header_b["keyframes"] > header_a["keyframes"] and header_b["rig"] == header_a["rig"] != "",
          "--load-map --save-map extends the map (%d -> %d keyframes)" % (header_a["keyframes"], header_b["keyframes"]))
    check(os.path.getsize(os.path.join(out_b, "map_static_loop.ply")) > 1000, "map_static_loop.ply written")
    # Localization only: loops to the map only, the map unchanged.
    out_c = os.path.join(work, "out_c")
    r = subprocess.run([idy, "run", "-c", cfg, "-d", seq_b, "-o", out_c, "--load-map", saved, "--localization-only"],
                       capture_output=True, text=True)
    lines = [l.split(",") for l in open(os.path.join(out_c, "loops.csv")) if not l.startswith("#")] \
        if r.returncode == 0 else []
    check(r.returncode == 0 and lines and all(l[11].strip() == "1" for l in lines),
          "--localization-only: %d loops, all to the map" % len(lines))
    # Misuse and a foreign map: one clear line, non-zero exit.
    foreign = os.path.join(os.path.dirname(cfg), "foreign.yaml")
    text = open(cfg).read()
    cam = os.path.join(os.path.dirname(cfg), [l.split('"')[1] for l in text.splitlines() if l.startswith("cam0_calib")][0])
    cam_text = open(cam).read()
    fx_line = [l for l in cam_text.splitlines() if l.strip().startswith("fx:")][0]
    foreign_cam = os.path.join(os.path.dirname(cfg), "foreign_cam0.yaml")
    open(foreign_cam, "w").write(cam_text.replace(fx_line, "   fx: 500.0"))
    open(foreign, "w").write(text.replace(os.path.basename(cam), "foreign_cam0.yaml"))
    for args, what, expect in (
            (["-c", foreign, "--load-map", saved], "a map from another camera", "another left camera"),
            (["-c", cfg, "--localization-only"], "--localization-only without a map", "--load-map"),
            (["-c", cfg, "--load-map", saved, "--localization-only", "--save-map", saved_b], "localization-only --save-map",
             "nothing to save")):
        r = subprocess.run([idy, "run", "-d", seq_b, "-o", os.path.join(work, "refused")] + args, capture_output=True,
                           text=True)
        lines = [l for l in r.stderr.splitlines() if l.strip() and l != "Run with --help for more information."]
        check(r.returncode != 0 and len(lines) == 1 and expect in lines[0], "%s refused: %s" % (what, r.stderr.strip()))


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
