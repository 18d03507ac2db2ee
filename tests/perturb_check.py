#!/usr/bin/python3
"""`idyvins perturb` faults run through `idyvins run` (CTest; the README's fault table comes from
`perturb_check.py IDYVINS WORK --table`).

An 8 s city-mid sequence; each fault at 4 s. Faults a robot must live with: the run completes, every
reset is reported with its cause, the trajectory is one piece (no step between consecutive poses more
than 0.2 m beyond what the truth moved) and the ATE over the whole file stays under 0.1 m (fault-free:
printed). Faults that make the data invalid (stamps going backwards or repeated, corrupt images):
one clear line and exit 1. IMU spikes beyond imu_max_acc are dropped as out of range; shorter than
imu_spike_max_ms and within it, by the spike gate (imu/spike_gate.h): both counted and said so.
"""
import json
import os
import shutil
import subprocess
import sys

HERE = os.path.dirname(os.path.abspath(__file__))
# (name, perturb arguments, expected: "ok" or the text of the one-line error)
CASES = [
    ("none", None, "ok"),
    ("imu-gap 0.5 s", ["--fault", "imu-gap", "--duration", "0.5"], "ok"),
    ("cameras and IMU silent 0.5 s", ["--fault", "silence", "--duration", "0.5"], "ok"),
    ("1 frame dropped", ["--fault", "frame-drop", "--count", "1"], "ok"),
    ("10 frames dropped (burst)", ["--fault", "frame-drop", "--count", "10"], "ok"),
    ("time jump +2 s", ["--fault", "time-jump", "--magnitude", "2"], "ok"),
    ("time jump -2 s", ["--fault", "time-jump", "--magnitude", "-2"], "non-increasing time stamp"),
    ("right camera 0.5 ms late for 0.5 s", ["--fault", "desync", "--magnitude", "0.5"], "ok"),
    ("right camera 3 ms late for 0.5 s", ["--fault", "desync", "--magnitude", "3"], "ok"),
    ("duplicated stamps 0.2 s", ["--fault", "duplicate-stamps", "--duration", "0.2"], "duplicate time stamp"),
    ("black images 1 s", ["--fault", "black", "--duration", "1"], "ok"),
    ("saturated images 0.5 s", ["--fault", "saturated", "--duration", "0.5"], "ok"),
    ("frozen images 0.5 s", ["--fault", "frozen", "--duration", "0.5"], "ok"),
    ("salt noise (10 %) 0.5 s", ["--fault", "salt", "--duration", "0.5"], "ok"),
    # A 25 ms spike of 10 g, within imu_max_acc: dropped by the spike gate.
    ("IMU spikes: 5 samples +100 m/s^2", ["--fault", "imu-spike", "--count", "5", "--magnitude", "100"], "ok"),
    ("IMU spikes: 5 samples +1000 m/s^2", ["--fault", "imu-spike", "--count", "5", "--magnitude", "1000"], "ok"),
    ("corrupt PNGs 0.1 s", ["--fault", "corrupt", "--duration", "0.1"], "truncated PNG"),
]
failures = []


def check(cond, what):
    print(("ok   " if cond else "FAIL ") + what, flush=True)
    if not cond:
        failures.append(what)


def tum(path):
    return [[float(x) for x in l.split()] for l in open(path) if l.strip() and not l.startswith("#")]


def largest_excess(est, gt_csv):
    gt = [[float(x) for x in l.split(",")[:4]] for l in open(gt_csv) if l.strip() and not l.startswith("#")]
    gt = [(r[0] * 1e-9, r[1:4]) for r in gt]

    def at(t):
        lo, hi = 0, len(gt) - 1
        while lo < hi:
            mid = (lo + hi) // 2
            if gt[mid][0] < t:
                lo = mid + 1
            else:
                hi = mid
        return gt[lo][1]

    def dist(a, b):
        return sum((x - y) ** 2 for x, y in zip(a, b)) ** 0.5
    return max([dist(b[1:4], a[1:4]) - dist(at(b[0]), at(a[0])) for a, b in zip(est, est[1:])] or [0.0])


def matrices(cfg):
    """body_T_cam0 and body_T_cam1 of a VINS-Fusion config (4 x 4, row-major lists)."""
    import yaml  # Debian's python3-yaml; the opencv-matrix tag read as a plain mapping
    yaml.SafeLoader.add_constructor("tag:yaml.org,2002:opencv-matrix", yaml.SafeLoader.construct_mapping)
    text = open(cfg).read().replace("%YAML:1.0", "")
    d = yaml.safe_load(text)
    import numpy as np
    return [np.array(d["body_T_cam%d" % i]["data"], dtype=float).reshape(4, 4) for i in (0, 1)]


def calibration_faults(idy, work, seq, cfg):
    """time-offset and extrinsic: what they write, checked against the source."""
    import numpy as np
    data = os.path.join(work, "time-offset")
    p = subprocess.run([idy, "perturb", seq, data, "--fault", "time-offset", "--magnitude", "30"], capture_output=True,
                       text=True)
    check(p.returncode == 0, "perturb time-offset: " + p.stderr.strip()[-200:])
    for sub in ["cam0", "cam1", "imu0", "state_groundtruth_estimate0"]:
        a = [l.split(",")[0] for l in open(os.path.join(seq, "mav0", sub, "data.csv")) if not l.startswith("#")]
        b = [l.split(",")[0] for l in open(os.path.join(data, "mav0", sub, "data.csv")) if not l.startswith("#")]
        shift = 30_000_000 if sub.startswith("cam") else 0
        check(len(a) == len(b) and all(int(x) - int(y) == shift for x, y in zip(a, b)),
              "time-offset 30 ms: %s stamps %s" % (sub, "30 ms earlier" if shift else "unchanged"))
    check(json.load(open(os.path.join(data, "perturb.json")))["td_true_ms"] == 30, "perturb.json: td_true_ms 30")
    truth = matrices(cfg)
    source_bytes = open(cfg, "rb").read()
    for camera in ["rig", "1"]:
        data = os.path.join(work, "extrinsic-" + camera)
        p = subprocess.run([idy, "perturb", seq, data, "--fault", "extrinsic", "--config", cfg, "--camera", camera,
                            "--rotation-deg", "3", "--translation-cm", "3"], capture_output=True, text=True)
        check(p.returncode == 0, "perturb extrinsic %s: %s" % (camera, p.stderr.strip()[-200:]))
        if p.returncode != 0:
            continue
        got = matrices(os.path.join(data, "config", os.path.basename(cfg)))
        for i in (0, 1):
            err = got[i] @ np.linalg.inv(truth[i])
            angle = np.degrees(np.arccos(np.clip((np.trace(err[:3, :3]) - 1) / 2, -1, 1)))
            moved = camera == "rig" or camera == str(i)
            # err = T_err * T - T: rotation 3 deg; translation 3 cm plus the rotation's lever on the camera's position
            want_t = np.linalg.norm(err[:3, 3]) > 0.0 if moved else True
            check((abs(angle - 3) < 1e-6 if moved else angle < 1e-9) and want_t,
                  "extrinsic %s: body_T_cam%d %s (%.6f deg)" % (camera, i, "3 deg off" if moved else "unchanged", angle))
        stereo = [np.linalg.inv(m[0]) @ m[1] for m in (truth, got)]
        kept = np.allclose(stereo[0], stereo[1], atol=1e-9)
        check(kept == (camera == "rig"), "extrinsic %s: the stereo pair's relative pose %s" % (
            camera, "kept" if camera == "rig" else "changed"))
        r = subprocess.run([idy, "run", "-c", os.path.join(data, "config", os.path.basename(cfg)), "-d", data, "-o",
                            data + "_out", "--mode", "baseline"], capture_output=True, text=True)
        check(r.returncode in (0, 4), "extrinsic %s: the perturbed config runs (exit %d)" % (camera, r.returncode))
    check(open(cfg, "rb").read() == source_bytes, "extrinsic: the source config unchanged (no write through a hard link)")
    p = subprocess.run([idy, "perturb", seq, os.path.join(work, "no-config"), "--fault", "extrinsic"],
                       capture_output=True, text=True)
    check(p.returncode != 0 and "needs the config" in p.stderr, "extrinsic without --config refused: " + p.stderr.strip())


def main(idy, work, table):
    shutil.rmtree(work, ignore_errors=True)
    os.makedirs(work)
    seq = os.path.join(work, "seq")
    r = subprocess.run([idy, "simulate", "--scene", "city", "--level", "mid", "--seed", "5", "--duration", "8", "--out",
                        seq], capture_output=True, text=True)
    check(r.returncode == 0, "simulate")
    cfg = os.path.join(seq, "config", "sim_stereo_imu_config.yaml")
    rows = []
    for name, args, expect in CASES:
        data = seq
        if args:
            data = os.path.join(work, name.split()[0] + "_" + str(len(rows)))
            p = subprocess.run([idy, "perturb", seq, data] + args, capture_output=True, text=True)
            check(p.returncode == 0, "perturb %s: %s" % (name, p.stderr.strip()[-200:]))
        out = data + "_out"
        r = subprocess.run([idy, "run", "-c", cfg, "-d", data, "-o", out, "--mode", "idy"], capture_output=True,
                           text=True)
        if expect != "ok":
            lines = [l for l in r.stderr.strip().split("\n") if l]
            check(r.returncode == 1 and len(lines) == 1 and expect in lines[0],
                  "%s: exit 1, one line naming the problem (%s)" % (name, lines[-1][-150:] if lines else ""))
            rows.append((name, "refused (exit 1): " + (lines[-1].split(": ", 1)[-1][:90] if lines else ""), "", "", ""))
            continue
        check(r.returncode == 0, "%s: run completes (%s)" % (name, r.stderr.strip()[-200:]))
        if r.returncode != 0:
            continue
        s = json.load(open(os.path.join(out, "stats.json")))["summary"]
        excess = largest_excess(tum(os.path.join(out, "trajectory.tum")),
                                os.path.join(data, "mav0", "state_groundtruth_estimate0", "data.csv"))
        resets = "; ".join("%s -> %s" % (x["why"], x["continued_by"] or "not resumed") for x in s["resets"]) or "none"
        segs = ", ".join("%.3f" % g["ate_rmse_m"] for g in s.get("segments", []) if g["ate_rmse_m"] is not None)
        rows.append((name, resets, "%.3f m" % s["ate_rmse_m"], segs, "%.2f m" % excess))
        check(s["ate_rmse_m"] < 0.1, "%s: ATE over the whole file %.3f m < 0.1 m" % (name, s["ate_rmse_m"]))
        check(excess < 0.2, "%s: one piece (largest step beyond the truth's %.3f m)" % (name, excess))
        check(all(x["resumed_t_ns"] >= 0 for x in s["resets"]), "%s: every reset followed by a new segment" % name)
        check(r.stdout.count("reset at") == len(s["resets"]), "%s: run prints each reset" % name)
        unpaired = s["unpaired_images"]
        if "3 ms late" in name:  # 10 frames of the window, each side without its partner
            check(unpaired["cam0"] == 10 and unpaired["cam1"] == 10 and "without a partner" in r.stdout,
                  "%s: 10 + 10 unpaired images counted and said so (%s)" % (name, unpaired))
        else:
            check(unpaired["cam0"] == 0 and unpaired["cam1"] == 0 and "without a partner" not in r.stdout,
                  "%s: no unpaired image reported" % name)
        dropped = s["imu_samples_dropped"]["out_of_range"]
        spiked = s["imu_samples_dropped"]["spikes"]
        if "1000" in name:
            check(dropped == 5 and "IMU samples dropped: 5" in r.stdout, "%s: 5 samples dropped and said so" % name)
        if "+100 " in name:
            check(dropped == 0 and spiked == 5 and s["imu_spikes"] == 1 and "1 IMU spikes dropped (5 samples" in r.stdout,
                  "%s: one spike of 5 samples dropped and said so" % name)
        else:
            check(spiked == 0, "%s: no IMU spike found (%d samples)" % (name, spiked))
    calibration_faults(idy, work, seq, cfg)
    if table:
        print("| fault (at 4 s) | resets: cause -> how it went on | ATE whole file | ATE per segment | largest step beyond the truth's |")
        print("| --- | --- | --- | --- | --- |")
        for row in rows:
            print("| " + " | ".join(row) + " |")
    return 1 if failures else 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1], sys.argv[2], "--table" in sys.argv))
