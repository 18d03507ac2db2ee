#!/usr/bin/python3
"""Plots for `idyvins bench` (called by it): trajectories vs ground truth (top view),
ATE over time, and the paper's Fig. 7 (d_s distribution before/after elimination with
the chi-square(1) fit; per-frame CV before/after). usage: bench_plots.py BENCH_DIR"""
import json
import os
import sys

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

out = sys.argv[1]
plots = os.path.join(out, "plots")
os.makedirs(plots, exist_ok=True)
results = json.load(open(os.path.join(out, "results.json")))
for r in results:  # run folders are relative to OUT (results.json is the same wherever the jobs ran)
    r["run"] = os.path.join(out, r["run"])


def align(P, Q):  # Umeyama SE3: Q ~ R P + t
    mp, mq = P.mean(0), Q.mean(0)
    U, _, Vt = np.linalg.svd((Q - mq).T @ (P - mp) / len(P))
    S = np.eye(3)
    if np.linalg.det(U) * np.linalg.det(Vt) < 0:
        S[2, 2] = -1
    R = U @ S @ Vt
    return (R @ P.T).T + (mq - R @ mp)


by_seq = {}
for r in results:
    by_seq.setdefault(r["sequence"], []).append(r)
for seq, runs in sorted(by_seq.items()):
    gt = np.loadtxt(os.path.join(runs[0]["dataset"], "mav0/state_groundtruth_estimate0/data.csv"), delimiter=",",
                    skiprows=1)
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5))
    a1.plot(gt[:, 1], gt[:, 2], "k-", lw=2, label="ground truth")
    for r in runs:
        path = os.path.join(r["run"], "trajectory.tum")
        if not os.path.exists(path) or os.path.getsize(path) < 100:
            continue
        est = np.atleast_2d(np.loadtxt(path))
        idx = np.searchsorted(gt[:, 0], est[:, 0] * 1e9 - 1e3)
        idx = np.clip(idx, 0, len(gt) - 1)
        A = align(est[:, 1:4], gt[idx, 1:4])
        a1.plot(A[:, 0], A[:, 1], lw=1, label=r["mode"])
        a2.plot(est[:, 0] - est[0, 0], np.linalg.norm(A - gt[idx, 1:4], axis=1), lw=1, label=r["mode"])
    a1.set_title(f"{seq}: top view (SE3-aligned)")
    a1.set_xlabel("x (m)")
    a1.set_ylabel("y (m)")
    a1.axis("equal")
    a1.legend(fontsize=8)
    a2.set_title("ATE over time")
    a2.set_xlabel("t (s)")
    a2.set_ylabel("position error (m)")
    a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(plots, f"{seq}_trajectories.png"), dpi=80)
    plt.close(fig)

# Fig. 7: d_s before/after elimination (idy), chi-square(1) fit; CV per frame.
for scene in ("city", "parking_lot"):
    fig, (a1, a2) = plt.subplots(1, 2, figsize=(13, 5))
    for level in ("none", "low", "mid", "high"):
        runs = [r for r in results if r["mode"] == "idy" and r["sequence"].startswith(f"{scene}_{level}_s")]
        if not runs:
            continue
        stats = json.load(open(os.path.join(runs[0]["run"], "stats.json")))["frames"]
        dyn = [f["dynamic"] for f in stats if f.get("dynamic") and f["dynamic"].get("prior")]
        if not dyn:
            continue
        before = np.sum([d["d_s_hist"] for d in dyn], axis=0).astype(float)
        after = np.sum([d["d_s_hist_kept"] for d in dyn], axis=0).astype(float)
        x = np.arange(len(before)) + 0.5
        a1.plot(x, before / before.sum(), "--", label=f"{level} before")
        a1.plot(x, after / after.sum(), "-", label=f"{level} after")
        if level == "high":
            cv_b = [d["cv_before"] for d in dyn]
            cv_a = [d["cv_after"] for d in dyn]
            a2.plot(cv_b, "b.", ms=2, label="CV before elimination")
            a2.plot(cv_a, "r.", ms=2, label="CV after elimination")
    # chi-square(1) pdf with the static scale (mean 1 px^2 as a reference), per 1 px^2 bin
    xs = np.linspace(0.05, 20, 400)
    a1.plot(xs, np.exp(-xs / 2) / np.sqrt(2 * np.pi * xs), "k:", label="chi-square(1) pdf")
    a1.set_yscale("log")
    a1.set_xlabel("d_s (px^2), 1 px^2 bins (last: >= 20)")
    a1.set_ylabel("fraction of tracked features")
    a1.set_title(f"{scene}: d_s before / after elimination (idy)")
    a1.legend(fontsize=7, ncol=2)
    a2.axhline(np.sqrt(2), color="k", lw=1, label="sqrt(2)")
    a2.set_xlabel("frame (with a motion prior)")
    a2.set_ylabel("coefficient of variation")
    a2.set_title(f"{scene} high: CV per frame")
    a2.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(os.path.join(plots, f"fig7_{scene}.png"), dpi=80)
    plt.close(fig)
print("plots written to", plots)
