#!/usr/bin/python3
"""The tables of bench/calibration.sh from its runs (WORK/runs: idyvins, WORK/vins: VINS-Fusion).

Usage: calibration_table.py WORK "OFFSETS" "TRAFFIC_SEQ_NAMES" SEQ_NAME...
Prints markdown: extrinsic faults, time offsets, IMU gaps and stereo alone, each run's ATE RMSE
(SE3, whole file) and its ratio to the exact run of the same program, the estimates against the
truth, and the worst ratio of each target over the sequences.
"""
import json
import math
import os
import re
import sys

import numpy as np

WORK, OFFSETS, TRAFFIC, SEQS = sys.argv[1], [int(x) for x in sys.argv[2].split()], sys.argv[3].split(), sys.argv[4:]
NAN = float("nan")


def summary(run):
    try:
        return json.load(open(os.path.join(WORK, "runs", run, "stats.json")))["summary"]
    except (OSError, ValueError, KeyError):
        return None


def ate(run):
    s = summary(run)
    return s.get("ate_rmse_m", NAN) if s else NAN


def resets(run):
    s = summary(run)
    return len(s["resets"]) if s else -1


def vins(run):
    try:
        return json.load(open(os.path.join(WORK, "vins", "vins_fusion_%s.ate.json" % run)))["rmse"]
    except (OSError, ValueError, KeyError):
        return NAN


def mount(seq):
    text = open(os.path.join(WORK, seq, "config", "sim_stereo_imu_config.yaml")).read()
    m = re.search(r"body_T_cam0:.*?data:\s*\[([^\]]*)\]", text, re.S)
    return np.array([float(x) for x in m.group(1).split(",")]).reshape(4, 4)


def extrinsic_error(run, seq):
    """Rotation (deg) and translation (cm) of the final cam0 estimate from the truth."""
    s = summary(run)
    if not s or not s.get("extrinsic") or math.isnan(s.get("ate_rmse_m", NAN)):  # no estimate: not initialized
        return NAN, NAN
    est, truth = np.array(s["extrinsic"]["body_T_cam"][0]), mount(seq)
    R = truth[:3, :3].T @ est[:3, :3]
    angle = math.degrees(math.acos(max(-1.0, min(1.0, (np.trace(R) - 1) / 2))))
    return angle, 100 * np.linalg.norm(est[:3, 3] - truth[:3, 3])


def m(x):
    return "x" if math.isnan(x) else "%.4f" % x


def r(a, b):
    return "x" if math.isnan(a) or math.isnan(b) or b == 0 else "%.2fx" % (a / b)


worst = {}


def track(key, a, b):
    if not (math.isnan(a) or math.isnan(b) or b == 0):
        worst[key] = max(worst.get(key, 0), a / b)
    elif not math.isnan(b):
        worst[key] = float("inf")


print("**Extrinsics** (ATE m; ratio to the same program's exact run; estimate error at the end)\n")
print("| sequence | exact | 1°/1 cm: as written (before) | 1°/1 cm: refined (now) | 3°/3 cm: before | 3°/3 cm: now | "
      "3°/3 cm now: estimate off | exact, refined | identity rotation, estimate_extrinsic 2 | 2: estimate off | "
      "VINS-Fusion: exact | 3°/3 cm, 0 | 3°/3 cm, 1 | identity, 2 |")
print("| --- " * 14 + "|")
for n in SEQS:
    R, ex = n, ate(n + ".exact")
    row = [n, m(ex)]
    for e in (1, 3):
        b, a = ate("%s.ex%d.est0" % (R, e)), ate("%s.ex%d.est1" % (R, e))
        row += ["%s (%s)" % (m(b), r(b, ex)), "%s (%s)" % (m(a), r(a, ex))]
        track("extrinsic %d°/%d cm, estimate_extrinsic 1 / exact (target 1.3x)" % (e, e), a, ex)
    rot, cm = extrinsic_error(R + ".ex3.est1", n)
    row.append("x" if math.isnan(rot) else "%.2f°, %.2f cm" % (rot, cm))
    worst["estimate off after 20 s, rotation (target 0.3°)"] = max(worst.get("estimate off after 20 s, rotation (target 0.3°)", 0), rot)
    worst["estimate off after 20 s, translation (target 1 cm)"] = max(worst.get("estimate off after 20 s, translation (target 1 cm)", 0), cm)
    e1 = ate(R + ".exact.est1")
    row.append("%s (%s)" % (m(e1), r(e1, ex)))
    track("exact, estimate_extrinsic 1 / 0 (target 1.05x)", e1, ex)
    i2 = ate(R + ".id.est2")
    row.append("%s (%s)" % (m(i2), r(i2, ex)))
    track("identity rotation, estimate_extrinsic 2 / exact (target 1.5x)", i2, ex)
    rot, cm = extrinsic_error(R + ".id.est2", n)
    row.append("x (not initialized)" if math.isnan(rot) else "%.2f°, %.2f cm" % (rot, cm))
    vx = vins(n + ".exact")
    row += [m(vx)] + ["%s (%s)" % (m(vins(n + k)), r(vins(n + k), vx)) for k in (".ex3.est0", ".ex3.est1", ".id.est2")]
    track("idyvins 3°/3 cm refined / VINS-Fusion refined (target 1x)", ate(R + ".ex3.est1"), vins(n + ".ex3.est1"))
    print("| " + " | ".join(row) + " |")

print("\n**Time offset** (ATE m; estimate_td 1 from td 0 against td given; td at the end)\n")
print("| sequence | offset | td given | from 0 (now) | td at the end | VINS-Fusion: td given | from 0 |")
print("| --- " * 7 + "|")
for n in SEQS:
    for o in OFFSETS:
        g, e = ate("%s.td%d.given" % (n, o)), ate("%s.td%d.est" % (n, o))
        s = summary("%s.td%d.est" % (n, o))
        td = 1e3 * s["td_s"] if s else NAN
        track("offset from 0 / td given (target 1.5x)", e, g)
        if not math.isnan(td):
            worst["offset estimate off at the end (target 1 ms)"] = max(worst.get("offset estimate off at the end (target 1 ms)", 0), abs(td - o))
        vg, ve = vins("%s.td%d.given" % (n, o)), vins("%s.td%d.est" % (n, o))
        print("| %s | %+d ms | %s | %s (%s) | %.2f ms | %s | %s (%s) |" % (n, o, m(g), m(e), r(e, g), td, m(vg), m(ve), r(ve, vg)))

print("\n**IMU gaps from 8 s, stereo alone** (ATE m, resets)\n")
print("| sequence | fault-free | 0.5 s gap | 2 s gap | imu: 0 | VINS-Fusion: fault-free | 0.5 s gap | 2 s gap | imu: 0 |")
print("| --- " * 9 + "|")
for n in SEQS:
    ex = ate(n + ".exact")
    cells = []
    for k in (".gap0.5", ".gap2"):
        a = ate(n + k)
        cells.append("%s, %d reset(s)" % (m(a), resets(n + k)))
        if not math.isnan(a) and not math.isnan(ex):
            worst["IMU gap / (2x fault-free + 1 cm) (target 1)"] = max(worst.get("IMU gap / (2x fault-free + 1 cm) (target 1)", 0), a / (2 * ex + 0.01))
    no = ate(n + ".noimu")
    track("imu: 0 / VINS-Fusion imu: 0 (target 1x)", no, vins(n + ".noimu"))
    print("| %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (n, m(ex), cells[0], cells[1], m(no), m(vins(n + ".exact")),
                                                          m(vins(n + ".gap0.5")), m(vins(n + ".gap2")), m(vins(n + ".noimu"))))

print("\n**Traffic** (ATE m; as rendered; estimate_extrinsic 1, estimate_td 1 from td 0; imu: 0: idy's "
      "constant-velocity prior)\n")
print("| sequence | baseline | idy | idy / baseline | baseline, estimating | idy, estimating | idy / baseline | "
      "baseline, imu: 0 | idy, imu: 0 | idy / baseline |")
print("| --- " * 10 + "|")
for n in TRAFFIC:
    pb, pi = ate(n + ".baseline.plain"), ate(n + ".idy.plain")
    b, i = ate(n + ".baseline.est"), ate(n + ".idy.est")
    bn, inn = ate(n + ".baseline.noimu"), ate(n + ".idy.noimu")
    target = 0.8 if n.endswith("_mid") else 0.6
    worst.setdefault("traffic, idy / baseline, estimating (target mid 0.8x, high 0.6x): worst ratio / target", 0)
    if not (math.isnan(b) or math.isnan(i)):
        k = "traffic, idy / baseline, estimating (target mid 0.8x, high 0.6x): worst ratio / target"
        worst[k] = max(worst[k], i / b / target)
    print("| %s | %s | %s | %s | %s | %s | %s | %s | %s | %s |" % (n, m(pb), m(pi), r(pi, pb), m(b), m(i), r(i, b), m(bn),
                                                                m(inn), r(inn, bn)))

print("\n**Worst over the sequences**\n")
print("| figure | worst |")
print("| --- | --- |")
for k, v in worst.items():
    print("| %s | %s |" % (k, "x (a run failed)" if v == float("inf") else "%.2f" % v))
