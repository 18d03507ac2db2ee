#!/usr/bin/python3
"""Cross-checks `idyvins eval --json` against an independent numpy implementation of
evo's published algorithms (evo/core/sync.py association, geometry.umeyama_alignment,
metrics APE/RPE translation part, filters.filter_pairs_by_path consecutive pairs).
evo itself cannot be installed here (no PyPI), so this is the next best referee.

usage: evo_reference_check.py IDYVINS_BINARY WORKDIR"""
import json
import os
import subprocess
import sys

import numpy as np


def quat_to_rot(qw, qx, qy, qz):
    return np.array([
        [1 - 2 * (qy * qy + qz * qz), 2 * (qx * qy - qz * qw), 2 * (qx * qz + qy * qw)],
        [2 * (qx * qy + qz * qw), 1 - 2 * (qx * qx + qz * qz), 2 * (qy * qz - qx * qw)],
        [2 * (qx * qz - qy * qw), 2 * (qy * qz + qx * qw), 1 - 2 * (qx * qx + qy * qy)]])


def random_rot(rng, scale):
    w = rng.normal(size=3) * scale
    th = np.linalg.norm(w)
    k = w / th
    K = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(th) * K + (1 - np.cos(th)) * K @ K


def rot_to_quat(R):  # w x y z
    w = np.sqrt(max(0.0, 1 + R[0, 0] + R[1, 1] + R[2, 2])) / 2
    x = np.copysign(np.sqrt(max(0.0, 1 + R[0, 0] - R[1, 1] - R[2, 2])) / 2, R[2, 1] - R[1, 2])
    y = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] + R[1, 1] - R[2, 2])) / 2, R[0, 2] - R[2, 0])
    z = np.copysign(np.sqrt(max(0.0, 1 - R[0, 0] - R[1, 1] + R[2, 2])) / 2, R[1, 0] - R[0, 1])
    q = np.array([w, x, y, z])
    return q / np.linalg.norm(q)


def make_data(workdir):
    rng = np.random.default_rng(7)
    # Reference: 200 Hz, 30 s, smooth 3D motion with rotation.
    t_ref = 1403715273.0 + np.arange(0, 30, 0.005)
    pos = np.stack([2 * np.sin(0.3 * (t_ref - t_ref[0])), np.cos(0.2 * (t_ref - t_ref[0])) * 3,
                    0.5 * np.sin(0.7 * (t_ref - t_ref[0]))], axis=1) + 0.01 * np.cumsum(rng.normal(size=(len(t_ref), 3)), 0)
    R = np.eye(3)
    rots = []
    for _ in t_ref:
        R = R @ random_rot(rng, 0.01)
        rots.append(R.copy())
    with open(os.path.join(workdir, "ref.tum"), "w") as f:
        f.write("# t x y z qx qy qz qw\n")
        for t, p, Rk in zip(t_ref, pos, rots):
            q = rot_to_quat(Rk)
            f.write(f"{t:.9f} {p[0]:.9f} {p[1]:.9f} {p[2]:.9f} {q[1]:.9f} {q[2]:.9f} {q[3]:.9f} {q[0]:.9f}\n")
    # Estimate: 20 Hz with 2 ms jitter, a gap, drift, noise, scale 1.03, in another frame; EuRoC CSV.
    Ra = random_rot(rng, 1.0)
    ta = np.array([3.0, -1.0, 0.5])
    with open(os.path.join(workdir, "est.csv"), "w") as f:
        f.write("#timestamp [ns],px,py,pz,qw,qx,qy,qz\n")
        for k in range(0, len(t_ref), 10):
            if 1500 <= k < 2500:
                continue
            t = t_ref[k] + rng.uniform(-0.002, 0.002)
            p = 1.03 * (Ra @ pos[k]) + ta + 0.02 * rng.normal(size=3) + 0.001 * k / 10 * np.array([1, 0.5, 0])
            q = rot_to_quat(Ra @ rots[k] @ random_rot(rng, 0.01))
            f.write(f"{int(round(t * 1e9))},{p[0]:.9f},{p[1]:.9f},{p[2]:.9f},{q[0]:.9f},{q[1]:.9f},{q[2]:.9f},{q[3]:.9f}\n")


def read_tum(path):
    d = np.loadtxt(path, comments="#")
    return d[:, 0], d[:, 1:4], [quat_to_rot(r[7], r[4], r[5], r[6]) for r in d]


def read_csv(path):
    d = np.loadtxt(path, delimiter=",", comments="#")
    return d[:, 0] * 1e-9, d[:, 1:4], [quat_to_rot(r[4], r[5], r[6], r[7]) for r in d]


def associate(t1, t2, max_diff):  # evo sync.associate_trajectories (traj_1 = ref, traj_2 = est)
    snd_longer = len(t2) > len(t1)
    short, long_ = (t1, t2) if snd_longer else (t2, t1)
    i_s, i_l = [], []
    for i, t in enumerate(short):
        diffs = np.abs(long_ - t)
        j = int(np.argmin(diffs))
        if diffs[j] <= max_diff:
            i_s.append(i)
            i_l.append(j)
    return (i_s, i_l) if snd_longer else (i_l, i_s)


def umeyama(x, y, with_scale):
    m, n = x.shape
    mx, my = x.mean(1), y.mean(1)
    sx = 1.0 / n * np.linalg.norm(x - mx[:, None]) ** 2
    cov = sum(np.outer(y[:, i] - my, x[:, i] - mx) for i in range(n)) / n
    u, d, v = np.linalg.svd(cov)
    s = np.eye(m)
    if np.linalg.det(u) * np.linalg.det(v) < 0:
        s[m - 1, m - 1] = -1
    r = u @ s @ v
    c = 1 / sx * np.trace(np.diag(d) @ s) if with_scale else 1.0
    return r, my - c * r @ mx, c


def stats(e):
    return {"rmse": np.sqrt(np.mean(e ** 2)), "mean": np.mean(e), "median": np.median(e), "std": np.std(e),
            "min": np.min(e), "max": np.max(e), "sse": np.sum(e ** 2)}


def se3(R, p):
    T = np.eye(4)
    T[:3, :3] = R
    T[:3, 3] = p
    return T


def rpe(ref_T, est_T, delta):
    ids, prev, path = [], est_T[0], 0.0
    for i, T in enumerate(est_T):
        path += np.linalg.norm(T[:3, 3] - prev[:3, 3])
        prev = T
        if path >= delta:
            ids.append(i)
            path = 0.0
    errs = []
    for i, j in zip(ids, ids[1:]):
        Q = np.linalg.inv(ref_T[i]) @ ref_T[j]
        P = np.linalg.inv(est_T[i]) @ est_T[j]
        errs.append(np.linalg.norm((np.linalg.inv(Q) @ P)[:3, 3]))
    return stats(np.array(errs))


def main():
    binary, workdir = sys.argv[1], sys.argv[2]
    os.makedirs(workdir, exist_ok=True)
    make_data(workdir)
    tr, pr, Rr = read_tum(os.path.join(workdir, "ref.tum"))
    te, pe, Re = read_csv(os.path.join(workdir, "est.csv"))
    ir, ie = associate(tr, te, 0.01)
    worst = 0.0
    for align in ("se3", "sim3", "none"):
        out = subprocess.run([binary, "eval", "--gt", os.path.join(workdir, "ref.tum"), "--est",
                              os.path.join(workdir, "est.csv"), "--align", align, "--rpe", "1,5", "--json"],
                             check=True, capture_output=True, text=True).stdout
        got = json.loads(out)
        x, y = pe[ie].T, pr[ir].T
        if align == "none":
            r, t, c = np.eye(3), np.zeros(3), 1.0
        else:
            r, t, c = umeyama(x, y, align == "sim3")
        aligned = (c * (r @ x)).T + t
        ref_stats = stats(np.linalg.norm(aligned - y.T, axis=1))
        assert got["pairs"] == len(ir), (got["pairs"], len(ir))
        for k, v in ref_stats.items():
            worst = max(worst, abs(got["ate"][k] - v))
            assert abs(got["ate"][k] - v) <= 1e-6, (align, k, got["ate"][k], v)
        ref_T = [se3(Rr[i], pr[i]) for i in ir]
        est_T = [se3(r @ Re[j], c * (r @ pe[j]) + t) for j in ie]
        for item in got["rpe"]:
            want = rpe(ref_T, est_T, item["delta_m"])
            for k, v in want.items():
                worst = max(worst, abs(item["stats"][k] - v))
                assert abs(item["stats"][k] - v) <= 1e-6, (align, item["delta_m"], k, item["stats"][k], v)
        print(f"align {align}: {len(ir)} pairs, ATE rmse {got['ate']['rmse']:.6f} m, matches numpy/evo rules")
    print(f"largest difference: {worst:.3e}")


if __name__ == "__main__":
    main()
