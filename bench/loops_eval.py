#!/usr/bin/env python3
"""Tables of the loop-closure and map-reuse benchmark (bench/loops.sh): OUT/loops.md and OUT/loops.json.

Looping sequences (DATA/{garage,block}_{none,high}_s{1,2,3}, each run in baseline and idy with loop
closure): odometry ATE (trajectory.tum) and loop ATE (trajectory_loop.tum), both SE(3)-aligned as
stats.json computes them; loops; false loops (a loop edge whose relative pose disagrees with the
ground truth by more than 0.3 m or 3 deg); the odometry's scale error and both ATEs after a similarity
alignment (a global scale error no loop can observe taken out); detection and pose-graph cost;
odometry time per frame.

Map reuse (a map built from traffic seed 11, the same place localized with traffic seed 12, other
traffic and the parked cars moved): time to the first relocalization, share of frames localized
(from the first relocalization on), relocalization error (the localized run's map poses against its
ground truth through the map run's alignment: no re-alignment), wrong relocalizations (loops to the
map failing the false-loop test), and the map's landmarks on the map run's temporarily parked cars.
Debian's python3 with numpy. Usage: loops_eval.py DATA_DIR OUT_DIR"""
import bisect
import json
import math
import os
import sys

import numpy as np

T0 = 1700000000000000000


def rotation(w, x, y, z):
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - z * w), 2 * (x * z + y * w)],
                     [2 * (x * y + z * w), 1 - 2 * (x * x + z * z), 2 * (y * z - x * w)],
                     [2 * (x * z - y * w), 2 * (y * z + x * w), 1 - 2 * (x * x + y * y)]])


def yaw(R):
    return math.atan2(R[1, 0], R[0, 0])


def ground_truth(dataset):
    gt = np.loadtxt(os.path.join(dataset, "mav0", "state_groundtruth_estimate0", "data.csv"), delimiter=",",
                    comments="#")
    ts = gt[:, 0].astype(np.int64)

    def pose(t):
        r = gt[min(bisect.bisect_left(ts, t), len(ts) - 1)]
        return r[1:4], rotation(*r[4:8])
    return pose


def loop_errors(dataset, loops_csv, map_dataset=None):
    """Per loop: translation (m) and yaw (rad) error of its relative pose against the ground truth,
    and to_map (a loop to a loaded map: the old keyframe's time is on map_dataset's clock; same
    world frame). tests/loop_check.py uses it too."""
    pose = ground_truth(dataset)
    map_pose = ground_truth(map_dataset) if map_dataset else pose
    out = []
    for line in open(loops_csv):
        if line.startswith("#"):
            continue
        f = line.strip().split(",")
        to_map = len(f) > 11 and f[11] == "1"
        p0, R0 = (map_pose if to_map else pose)(int(f[0]))
        p1, R1 = pose(int(f[1]))
        d_t = np.linalg.norm(R0.T @ (p1 - p0) - np.array([float(v) for v in f[7:10]]))
        d_yaw = abs((yaw(R1) - yaw(R0) - float(f[10]) + math.pi) % (2 * math.pi) - math.pi)
        out.append((d_t, d_yaw, to_map))
    return out


def false_loops(errors):
    return sum(1 for e in errors if e[0] > 0.3 or e[1] > math.radians(3))


def read_tum(path):
    rows = np.array([[float(v) for v in l.split()] for l in open(path) if l.strip() and not l.startswith("#")])
    return (rows[:, 0] * 1e9).round().astype(np.int64), rows[:, 1:4]


def umeyama_se3(src, dst):
    """R, t minimizing |R src + t - dst| (no scale)."""
    ms, md = src.mean(0), dst.mean(0)
    U, _, Vt = np.linalg.svd((dst - md).T @ (src - ms))
    R = U @ np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))]) @ Vt
    return R, md - R @ ms


def ate_sim3(dataset, tum):
    """(RMSE m, scale) of a TUM trajectory against the ground truth after a similarity alignment
    (Umeyama with scale): what is left when a global scale error, which no loop can observe, is
    taken out. scale < 1: the estimate is too large."""
    gt = ground_truth(dataset)
    t, p = read_tum(tum)
    g = np.array([gt(x)[0] for x in t])
    X, Y = p - p.mean(0), g - g.mean(0)
    U, S, Vt = np.linalg.svd(Y.T @ X)
    D = np.diag([1, 1, np.sign(np.linalg.det(U @ Vt))])
    R = U @ D @ Vt
    scale = np.trace(np.diag(S) @ D) / (X ** 2).sum()
    return float(np.sqrt((np.linalg.norm(scale * X @ R.T - Y, axis=1) ** 2).mean())), float(scale)


def read_ply_xyz(path):
    with open(path) as f:
        for line in f:
            if line.strip() == "end_header":
                break
        rows = [l.split()[:3] for l in f if l.strip()]
    return np.array(rows, dtype=float).reshape(-1, 3)


def summary(out):
    return json.load(open(os.path.join(out, "stats.json")))["summary"]


def looping(data, out_dir):
    rows = []
    runs = [("%s_%s_s%d" % (place, level, seed), mode) for place in ("garage", "block") for level in ("none", "high")
            for seed in (1, 2, 3) for mode in ("baseline", "idy")]
    runs += [("validation_garage_%s_s1" % level, "idy") for level in ("none", "high")]
    for seq, mode in runs:
        out = os.path.join(out_dir, "%s_%s" % (seq, mode))
        if not os.path.exists(os.path.join(out, "stats.json")):
            rows.append({"sequence": seq, "mode": mode, "missing": True})
            continue
        s = summary(out)
        lc = s["loop_closure"]
        errors = loop_errors(os.path.join(data, seq), os.path.join(out, "loops.csv"))
        odo_sim3, scale = ate_sim3(os.path.join(data, seq), os.path.join(out, "trajectory.tum"))
        loop_sim3 = ate_sim3(os.path.join(data, seq), os.path.join(out, "trajectory_loop.tum"))[0] \
            if os.path.exists(os.path.join(out, "trajectory_loop.tum")) else None
        frame_ms = s["mean_tracking_ms"] + s["mean_optimization_ms"] + s["mean_marginalization_ms"] + \
            s["mean_filter_ms"]
        rows.append({"sequence": seq, "mode": mode, "ate_m": s.get("ate_rmse_m"),
                     "loop_ate_m": lc.get("ate_rmse_m"), "loops": lc["loops"],
                     "ate_sim3_m": odo_sim3, "loop_ate_sim3_m": loop_sim3, "scale_error_pct": 100 * (1 / scale - 1),
                     "false_loops": false_loops(errors),
                     "worst_loop_m": max((e[0] for e in errors), default=0.0),
                     "worst_loop_deg": math.degrees(max((e[1] for e in errors), default=0.0)),
                     "keyframes": lc["keyframes"], "detect_ms_per_keyframe": lc["mean_detect_ms_per_keyframe"],
                     "graph_ms_per_solve": lc["mean_graph_ms_per_solve"], "graph_solves": lc["graph_solves"],
                     "frame_ms": frame_ms, "realtime_factor": s["realtime_factor"],
                     "resets": len(s["resets"])})
    return rows


def reuse(data, out_dir):
    rows = []
    for place in ("garage", "block"):
        map_seq, loc_seq = os.path.join(data, "reuse_%s_t11" % place), os.path.join(data, "reuse_%s_t12" % place)
        for mode in ("baseline", "idy"):
            map_out = os.path.join(out_dir, "reuse_%s_map_%s" % (place, mode))
            loc_out = os.path.join(out_dir, "reuse_%s_loc_%s" % (place, mode))
            if not (os.path.exists(os.path.join(map_out, "stats.json")) and
                    os.path.exists(os.path.join(loc_out, "stats.json"))):
                rows.append({"place": place, "mode": mode, "missing": True})
                continue
            sm, sl = summary(map_out), summary(loc_out)
            m = sl["loop_closure"]["map"]
            row = {"place": place, "mode": mode, "map_keyframes": m["loaded_keyframes"],
                   "map_odometry_ate_m": sm.get("ate_rmse_m"), "map_loop_ate_m": sm["loop_closure"].get("ate_rmse_m"),
                   "map_static_on_moving_pct": 100 * sm["classification"]["static_map_fraction_on_moving"],
                   "relocalized": m["relocalized"], "unconfirmed_matches": m["unconfirmed_matches"],
                   "loops_to_map": m["loops_to_map"], "loc_odometry_ate_m": sl.get("ate_rmse_m")}
            # the map frame in the world: the map run's corrected trajectory aligned to its ground truth
            gt_map, gt_loc = ground_truth(map_seq), ground_truth(loc_seq)
            ta, pa = read_tum(os.path.join(map_out, "trajectory_loop.tum"))
            R, t = umeyama_se3(pa, np.array([gt_map(x)[0] for x in ta]))
            # landmarks of the map on the map run's temporarily parked cars (boxes grown by 0.15 m)
            pts = read_ply_xyz(os.path.join(map_out, "map_static_loop.ply")) @ R.T + t
            parked = json.load(open(os.path.join(map_seq, "meta.json")))["parked_vehicles"]
            on = np.zeros(len(pts), dtype=bool)
            for box in parked:
                lo, hi = np.array(box["min"]) - 0.15, np.array(box["max"]) + 0.15
                on |= np.all((pts >= lo) & (pts <= hi), axis=1)
            row["map_landmarks"] = int(len(pts))
            row["map_landmarks_on_parked"] = int(on.sum())
            errors = loop_errors(loc_seq, os.path.join(loc_out, "loops.csv"), map_dataset=map_seq)
            row["wrong_relocalizations"] = false_loops([e for e in errors if e[2]])
            frames = sl["frames"]
            if m["relocalized"]:
                first = m["first_relocalization_t_ns"]
                row["first_relocalization_s"] = (first - sl["first_t_ns"]) / 1e9
                tb, pb = read_tum(os.path.join(loc_out, "trajectory_loop.tum"))
                after = tb >= first
                err = np.linalg.norm(pb[after] @ R.T + t - np.array([gt_loc(x)[0] for x in tb[after]]), axis=1)
                row["localized_share"] = float(after.sum()) / frames
                row["relocalization_rmse_m"] = float(np.sqrt((err ** 2).mean()))
                row["relocalization_max_m"] = float(err.max())
            rows.append(row)
    return rows


def fmt(v, f="%.3f"):
    return "—" if v is None else f % v


def summary_table(loop_rows):
    """Per place, traffic and mode: runs, loop/odometry ATE ratio (worst and mean), false loops."""
    out = ["| sequences | mode | runs | loop / odometry ATE, worst (mean) | the same, scale aligned | false loops |",
           "|---|---|---|---|---|---|"]
    groups = {}
    for r in loop_rows:
        if r.get("missing") or r["ate_m"] is None or r["loop_ate_m"] is None:
            continue
        key = (r["sequence"].rsplit("_s", 1)[0], r["mode"])
        groups.setdefault(key, []).append(r)
    for (seq, mode), rows in sorted(groups.items()):
        ratios = [r["loop_ate_m"] / r["ate_m"] for r in rows]
        sim3 = [r["loop_ate_sim3_m"] / r["ate_sim3_m"] for r in rows]
        out.append("| %s | %s | %d | %.2f (%.2f) | %.2f (%.2f) | %d |" % (
            seq, mode, len(rows), max(ratios), sum(ratios) / len(ratios), max(sim3), sum(sim3) / len(sim3),
            sum(r["false_loops"] for r in rows)))
    return out


def markdown(loop_rows, reuse_rows):
    out = ["## Looping sequences (3 min; loop closure on)", ""] + summary_table(loop_rows) + ["",
           "| sequence | mode | odometry ATE (m) | loop ATE (m) | loop / odometry | odometry scale error | "
           "scale aligned: odometry / loop ATE (m) | loops | false loops | worst loop "
           "(m, °) | keyframes | detect ms/kf | graph solves, ms each | graph ms/kf | resets |",
           "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in loop_rows:
        if r.get("missing"):
            out.append("| %s | %s | not run ||||||||||||| |" % (r["sequence"], r["mode"]))
            continue
        ratio = r["loop_ate_m"] / r["ate_m"] if r["ate_m"] and r["loop_ate_m"] is not None else None
        out.append("| %s | %s | %s | %s | %s | %+.2f %% | %.3f / %s | %d | %d | %.3f, %.2f | %d | %.0f | %d, %.0f | %.0f "
                   "| %d |" % (
            r["sequence"], r["mode"], fmt(r["ate_m"]), fmt(r["loop_ate_m"]), fmt(ratio, "%.2f"), r["scale_error_pct"],
            r["ate_sim3_m"], fmt(r["loop_ate_sim3_m"]), r["loops"],
            r["false_loops"], r["worst_loop_m"], r["worst_loop_deg"], r["keyframes"], r["detect_ms_per_keyframe"],
            r["graph_solves"], r["graph_ms_per_solve"],
            r["graph_ms_per_solve"] * r["graph_solves"] / max(1, r["keyframes"]), r["resets"]))
    out += ["", "## Map reuse under new traffic (map: traffic seed 11; localized: traffic seed 12, --localization-only)",
            "", "| place | map built by | map run ATE, odometry / loop (m) | map run's static map on moving objects | map landmarks | on parked cars | first "
            "relocalization (s) | frames localized | relocalization RMSE (m) | max (m) | localized run ATE (m) | "
            "loops to map | wrong relocalizations | unconfirmed matches |",
            "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in reuse_rows:
        if r.get("missing"):
            out.append("| %s | %s | not run ||||||||||| |" % (r["place"], r["mode"]))
            continue
        out.append("| %s | %s | %s / %s | %.2f %% | %d | %d (%.1f %%) | %s | %s | %s | %s | %s | %d | %d | %d |" % (
            r["place"], r["mode"], fmt(r["map_odometry_ate_m"]), fmt(r["map_loop_ate_m"]), r["map_static_on_moving_pct"],
            r["map_landmarks"],
            r["map_landmarks_on_parked"],
            100.0 * r["map_landmarks_on_parked"] / max(1, r["map_landmarks"]), fmt(r.get("first_relocalization_s"), "%.1f"),
            fmt(100 * r["localized_share"] if "localized_share" in r else None, "%.1f %%"),
            fmt(r.get("relocalization_rmse_m")), fmt(r.get("relocalization_max_m")), fmt(r["loc_odometry_ate_m"]),
            r["loops_to_map"],
            r["wrong_relocalizations"], r["unconfirmed_matches"]))
    return "\n".join(out) + "\n"


def main(data, out_dir):
    loop_rows, reuse_rows = looping(data, out_dir), reuse(data, out_dir)
    json.dump({"looping": loop_rows, "reuse": reuse_rows}, open(os.path.join(out_dir, "loops.json"), "w"), indent=1)
    text = markdown(loop_rows, reuse_rows)
    open(os.path.join(out_dir, "loops.md"), "w").write(text)
    print(text)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2]))
