#!/usr/bin/python3
"""The disparity error of the right matches against the rendered truth, pixel by pixel.

Usage: scripts/analysis/disparity_error.py OBS.csv DATASET [--frames N] [--every K] [--json OUT.json]
(Debian python3 with numpy, yaml, cv2: python3-opencv)

DATASET is a render written with `idyvins simulate --depth`; OBS.csv is `idyvins run
--dump-observations` of it. For every static observation with a right match, the left
pixel is lifted with the left camera's rendered depth (inverse depth interpolated
bilinearly: exact on a plane) and projected into the right camera with the calibration
and the ground truth: that is where the right match of this left pixel must be. The
disparity error is found - true disparity along the epipolar line (negative: disparity too
small, depth too large, a path too long). Left pixels on a depth step or the sky's edge
(7 x 7 px depth not within 20 %, or touching the sky) are counted apart: their truth is
not one surface.

The same left pixels are matched again in the same right images with OpenCV's pyramidal
LK at idyvins' settings (13 px, 4 levels, right image gain-compensated) and at
VINS-Fusion's (21 px, 3 levels, 30 iterations, epsilon 0.01, no compensation), so that
the three are compared on the same matches. Each match's LK iteration count is found by
re-running it with 1, 2, 3, 5 and 10 iterations (the first cap whose result is within
0.01 px of the uncapped one).

Prints, per matcher, the mean (median) disparity error binned by true disparity, surface
slant (angle between the surface normal and the viewing ray: 90 is grazing), texture
contrast (gray-level standard deviation of the left 13 x 13 patch), image row, sub-pixel
phase of the true right u (pixel locking shows as a pattern over the phase) and iteration
count, with each bin's share of the matches. --json writes the same tables.
"""
import argparse
import csv
import json
import sys
from collections import defaultdict

import cv2
import numpy as np

from sim_geometry import Rig

parser = argparse.ArgumentParser(usage=__doc__)
parser.add_argument('obs')
parser.add_argument('dataset')
parser.add_argument('--frames', type=int, default=0, help='only the first N frames (0: all)')
parser.add_argument('--every', type=int, default=1, help='every K-th frame')
parser.add_argument('--json', default='')
parser.add_argument('--rows', default='', help='write every match row (numpy .npy of a dict) for further study')
parser.add_argument('--effects', default='',
                    help='comma-separated camera effects applied to both images before the LK matchers (not to the '
                         "tracker's matches): contrast (texture contrast x 0.25 around the mean), defocus (Gaussian, "
                         '1.2 px), vignetting (k1 -0.35, k2 0.05), darker (right image x 0.9), noise (shot, 6000 e- '
                         'full well, and 1.5 gray levels read noise), then 8-bit rounding: the euroc realism preset\'s '
                         'values, to find which one makes a bias')
parser.add_argument('--translation', action='store_true',
                    help='also refine the LK matches by a gain- and offset-invariant translation-only alignment')
parser.add_argument('--converged', action='store_true',
                    help='also match with 100 iterations and a 1e-4 px stopping step')
parser.add_argument('--devignette', nargs=2, type=float, metavar=('K1', 'K2'),
                    help='also match on images divided by the vignetting V(r) = 1 + k1 r^2 + k2 r^4 '
                         '(r: distance to the principal point over the half diagonal, as simulate --realism)')
args = parser.parse_args()
ds = args.dataset
rig = Rig(ds)

by_frame = defaultdict(list)
with open(args.obs) as f:
    for r in csv.DictReader(f):
        if r['on_moving'] == '1' or not r.get('u_right'):
            continue
        by_frame[int(r['t_ns'])].append((float(r['u']), float(r['v']), float(r['u_right']), float(r['v_right'])))
frames = sorted(by_frame)
if args.frames:
    frames = frames[:args.frames]
frames = frames[::args.every]
if not frames:
    sys.exit(f'{args.obs}: no static observation with a right match (u_right)')


def read(path, flags):
    img = cv2.imread(path, flags)
    if img is None:
        sys.exit(f'{path}: cannot read (a render written with simulate --depth is expected)')
    return img


def match_brightness(image, reference):
    """idyvins' stereo_gain_compensation: the right image's mean and spread mapped to the left's."""
    mi, si = cv2.meanStdDev(image)
    mr, sr = cv2.meanStdDev(reference)
    a = sr[0, 0] / si[0, 0]
    b = mr[0, 0] - a * mi[0, 0]
    if abs(a - 1) <= 0.02 and abs(mi[0, 0] / mr[0, 0] - 1) <= 0.02:
        return image
    return cv2.convertScaleAbs(image, alpha=a, beta=b)


EFFECTS = {'contrast', 'defocus', 'vignetting', 'darker', 'noise'}
effects = [e for e in args.effects.split(',') if e]
if set(effects) - EFFECTS:
    sys.exit(f'--effects: unknown {sorted(set(effects) - EFFECTS)}, expected some of {sorted(EFFECTS)}')
rng = np.random.default_rng(1)


def apply_effects(image, cam):
    out = image.astype(np.float64)
    if 'contrast' in effects:
        out = out.mean() + 0.25 * (out - out.mean())
    if 'defocus' in effects:
        out = cv2.GaussianBlur(out, (0, 0), 1.2)
    if 'vignetting' in effects:
        h, w = out.shape
        k = rig.K[cam]
        y, x = np.mgrid[0:h, 0:w]
        r2 = ((x - k['cx']) ** 2 + (y - k['cy']) ** 2) / (0.25 * (w * w + h * h))
        out = out * (1 - 0.35 * r2 + 0.05 * r2 * r2)
    if 'darker' in effects and cam == 1:
        out = out * 0.9
    if 'noise' in effects:
        out = out + rng.normal(size=out.shape) * np.sqrt(np.maximum(out, 0) * 255 / 6000 + 1.5 ** 2)
    return np.clip(np.round(out), 0, 255).astype(np.uint8) if effects else image


def normalized_patch(image, uv, n):
    p = cv2.getRectSubPix(image, (n, n), (float(uv[0]), float(uv[1])), patchType=cv2.CV_32F).astype(np.float64)
    p -= p.mean()
    norm = np.sqrt((p * p).sum())
    return p / norm if norm > 1e-6 else None


def warped_patch(image, A, t, xs, ys):
    mx = A[0, 0] * xs + A[0, 1] * ys + t[0]
    my = A[1, 0] * xs + A[1, 1] * ys + t[1]
    if mx.min() < 0 or my.min() < 0 or mx.max() > image.shape[1] - 2 or my.max() > image.shape[0] - 2:
        return None
    x0, y0 = np.floor(mx).astype(int), np.floor(my).astype(int)
    ax, ay = mx - x0, my - y0  # bilinear in float: cv2.remap rounds positions to 1/32 px
    img = image.astype(np.float64)
    p = ((1 - ay) * ((1 - ax) * img[y0, x0] + ax * img[y0, x0 + 1]) +
         ay * ((1 - ax) * img[y0 + 1, x0] + ax * img[y0 + 1, x0 + 1]))
    p -= p.mean()
    norm = np.sqrt((p * p).sum())
    return p / norm if norm > 1e-6 else None


def normalized_template(left, uv_l, half):
    """The left (2 half + 1)^2 patch at uv_l, zero-mean and unit-norm, with its central-difference
    gradients on the same scale; None when flat (below about one gray level of spread)."""
    n = 2 * half + 1
    big = cv2.getRectSubPix(left, (n + 2, n + 2), (float(uv_l[0]), float(uv_l[1])), patchType=cv2.CV_32F)
    big = big.astype(np.float64)
    t = big[1:-1, 1:-1]
    norm = np.sqrt(((t - t.mean()) ** 2).sum())
    if norm < n:
        return None
    gx = 0.5 * (big[1:-1, 2:] - big[1:-1, :-2]) / norm
    gy = 0.5 * (big[2:, 1:-1] - big[:-2, 1:-1]) / norm
    return (t - t.mean()) / norm, gx, gy


def align_stereo_warp(left, right, uv_l, uv_r, half):
    """The right match refined by a gain- and offset-invariant alignment whose warp is a translation
    and, along the rows, the foreshortening of a slanted plane (u' = (1 + a) x + b y + tu, v' = y + tv;
    inverse compositional): None when flat or not converged."""
    n = 2 * half + 1
    template = normalized_template(left, uv_l, half)
    if template is None:
        return None
    T, gx, gy = template
    ys, xs = np.mgrid[-half:half + 1, -half:half + 1].astype(np.float64)
    sd = np.stack([gx * xs, gx * ys, gx, gy]).reshape(4, -1)
    H = sd @ sd.T
    if np.linalg.cond(H) > 1e9:
        return None
    H_inv = np.linalg.inv(H)
    A, tr = np.eye(2), np.array(uv_r, float)
    for _ in range(30):
        W = warped_patch(right, A, tr, xs, ys)
        if W is None:
            return None
        d = H_inv @ (sd @ (W - T).ravel())
        inc = np.array([[1 + d[0], d[1]], [0, 1]])
        inc_inv = np.linalg.inv(inc)
        A = A @ inc_inv
        tr = tr - A @ d[2:]
        if np.abs(d[2:]).max() < 1e-3 and np.abs(d[:2]).max() < 1e-4:
            return tr
    return None


def align_translation(left, right, uv_l, uv_r, half):
    """The right match refined by a gain- and offset-invariant translation-only alignment (inverse
    compositional, both (2 half + 1)^2 patches zero-mean and unit-norm): None when flat or not converged."""
    n = 2 * half + 1
    template = normalized_template(left, uv_l, half)
    if template is None:
        return None
    T, gx, gy = template
    H = np.array([[(gx * gx).sum(), (gx * gy).sum()], [(gx * gy).sum(), (gy * gy).sum()]])
    if np.linalg.det(H) < 1e-12:
        return None
    H_inv = np.linalg.inv(H)
    p = np.array(uv_r, float)
    for _ in range(20):
        W = normalized_patch(right, p, n)
        if W is None:
            return None
        e = W - T
        step = H_inv @ np.array([(gx * e).sum(), (gy * e).sum()])
        p -= step
        if np.linalg.norm(step) < 1e-4:
            return p
    return None


def lift(depth, uv):
    """The left pixel's camera point and group (surface / edge / sky), or None at the border."""
    iu, iv = int(np.floor(uv[0])), int(np.floor(uv[1]))
    if iu < 3 or iv < 3 or iu > depth.shape[1] - 5 or iv > depth.shape[0] - 5:
        return None, None, None
    around = depth[iv - 3:iv + 5, iu - 3:iu + 5]
    if (around <= 0).any():
        return 'sky', None, None
    if around.max() / around.min() > 1.2:
        return 'edge', None, None
    a, b = uv[0] - iu, uv[1] - iv
    four = depth[iv:iv + 2, iu:iu + 2].astype(float)
    w = np.array([[(1 - a) * (1 - b), a * (1 - b)], [(1 - a) * b, a * b]])
    z = 1.0 / (w / four).sum()
    # Surface normal from the 5 x 5 pixels around: a plane through their lifted points.
    pts = []
    for dv in range(-2, 3):
        for du in range(-2, 3):
            pu, pv = iu + du, iv + dv
            pts.append(rig.normalized(0, (pu, pv)) * depth[pv, pu])
    pts = np.array(pts)
    c = pts.mean(axis=0)
    n = np.linalg.svd(pts - c)[2][2]
    ray = rig.normalized(0, uv)
    slant = np.degrees(np.arccos(min(1.0, abs(n @ ray) / np.linalg.norm(ray))))
    return 'surface', ray * z, slant


matchers = {'idyvins tracker': None, 'LK 13 px x 4, compensated': (13, 4, True, 30, 0.01),
            'LK 21 px x 3 (VINS-Fusion)': (21, 3, False, 30, 0.01)}
if args.converged:
    matchers['LK 13 px x 4, compensated, 100 iterations, epsilon 1e-4'] = (13, 4, 'converged', 100, 1e-4)
if args.translation:
    matchers['LK 13 px x 4, then gain/offset-invariant translation, 13 px'] = (13, 4, 'translation', 30, 0.01)
    matchers['LK 13 px x 4, then gain/offset-invariant stereo warp, 13 px'] = (13, 4, 'stereo warp', 30, 0.01)
if args.devignette:
    matchers['LK 13 px x 4, compensated, devignetted'] = (13, 4, 'devignette', 30, 0.01)


def devignette(image, cam):
    h, w = image.shape
    k = rig.K[cam]
    y, x = np.mgrid[0:h, 0:w]
    r2 = ((x - k['cx']) ** 2 + (y - k['cy']) ** 2) / (0.25 * (w * w + h * h))
    v = 1 + args.devignette[0] * r2 + args.devignette[1] * r2 * r2
    return np.clip(image / v, 0, 255).astype(np.uint8)
rows = {name: [] for name in matchers}  # (disparity err, true disparity, slant, contrast, row, phase, iterations, left u, err across)
groups = defaultdict(int)
crit = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, 30, 0.01)
for t in frames:
    depth = read(f'{ds}/mav0/cam0/depth/{t}.tiff', cv2.IMREAD_UNCHANGED)
    left = read(f'{ds}/mav0/cam0/data/{t}.png', cv2.IMREAD_GRAYSCALE)
    right = read(f'{ds}/mav0/cam1/data/{t}.png', cv2.IMREAD_GRAYSCALE)
    left_fx, right_fx = apply_effects(left, 0), apply_effects(right, 1)
    R0, p0 = rig.pose[t][0]
    keep = []
    for u, v, ur, vr in by_frame[t]:
        group, X_c0, slant = lift(depth, (u, v))
        if group is None:
            continue
        groups[group] += 1
        if group != 'surface':
            continue
        X = R0 @ X_c0 + p0
        q, z = rig.project(1, t, X)
        q_far, _ = rig.project(1, t, p0 + (X - p0) * 1.01)
        e = (q_far - q) / np.linalg.norm(q_far - q)  # right image direction of a smaller disparity
        # The true disparity: how far the right point lies from the point at infinity.
        q_inf, _ = rig.project(1, t, p0 + (X - p0) * 1e6)
        patch = left[int(round(v)) - 6:int(round(v)) + 7, int(round(u)) - 6:int(round(u)) + 7]
        keep.append(((u, v), (ur, vr), q, e, np.linalg.norm(q_inf - q), slant, float(patch.std()), v))
    if not keep:
        continue
    pl = np.array([k[0] for k in keep], np.float32)
    found = {'idyvins tracker': np.array([k[1] for k in keep])}
    iterations = None
    for name, spec in matchers.items():
        if spec is None:
            continue
        w, levels, comp, max_iter, eps = spec
        img_l = devignette(left_fx, 0) if comp == 'devignette' else left_fx
        img_r = devignette(right_fx, 1) if comp == 'devignette' else right_fx
        img_r = match_brightness(img_r, img_l) if comp else img_r
        out, st, _ = cv2.calcOpticalFlowPyrLK(img_l, img_r, pl.copy(), None, winSize=(w, w), maxLevel=levels,
                                              criteria=(crit[0], max_iter, eps))
        res = out.astype(float)
        res[st[:, 0] == 0] = np.nan
        if comp in ('translation', 'stereo warp'):
            align = align_translation if comp == 'translation' else align_stereo_warp
            for j in range(len(res)):
                if np.isfinite(res[j, 0]):
                    q = align(img_l, img_r, pl[j], res[j], w // 2)
                    res[j] = q if q is not None and np.linalg.norm(q - res[j]) < 1 else np.nan
        found[name] = res
        if comp is True:  # the iteration count of idyvins' own stereo search
            iterations = np.full(len(pl), 30.0)
            for cap in [10, 5, 3, 2, 1]:
                c = (cv2.TERM_CRITERIA_COUNT | cv2.TERM_CRITERIA_EPS, cap, 0.01)
                o, _, _ = cv2.calcOpticalFlowPyrLK(img_l, img_r, pl.copy(), None, winSize=(w, w), maxLevel=levels,
                                                   criteria=c)
                same = np.linalg.norm(o - out, axis=1) < 0.01
                iterations[same] = cap
    for name, pts in found.items():
        for j, k in enumerate(keep):
            d = pts[j] - k[2]
            if not np.all(np.isfinite(d)) or np.linalg.norm(d) > 3:
                continue
            across = d @ np.array([-k[3][1], k[3][0]])  # the error across the epipolar line
            rows[name].append((-(d @ k[3]), k[4], k[5], k[6], k[7], k[2][0] % 1.0, iterations[j], k[0][0], across))

height = cv2.imread(f'{ds}/mav0/cam0/data/{frames[0]}.png', cv2.IMREAD_GRAYSCALE).shape[0]
bins = {
    'true disparity (px)': (1, [0, 2, 5, 10, 20, 40, 1e9]),
    'slant (deg, 90 grazing)': (2, [0, 30, 60, 75, 85, 90.1]),
    'texture contrast (gray std)': (3, [0, 5, 10, 20, 40, 1e9]),
    'image row': (4, list(np.linspace(0, height, 6))),
    'sub-pixel phase of true u': (5, list(np.linspace(0, 1, 6))),
    'LK iterations': (6, [0, 1.5, 2.5, 3.5, 5.5, 10.5, 31]),
}
total_groups = sum(groups.values())
print(f'{len(frames)} frames; left pixels: ' +
      ', '.join(f'{g} {100 * n / total_groups:.1f} %' for g, n in sorted(groups.items())) + ' (edge and sky not scored)')
report = {'frames': len(frames), 'groups': dict(groups), 'matchers': {}}
for name, r in rows.items():
    r = np.array(r)
    if not len(r):
        continue
    out = {'matches': len(r), 'mean': r[:, 0].mean(), 'median': float(np.median(r[:, 0])),
           'mad': float(np.median(np.abs(r[:, 0] - np.median(r[:, 0])))), 'bins': {}}
    print(f'\n{name}: {len(r)} matches, disparity error mean {out["mean"]:+.4f} median {out["median"]:+.4f} px, '
          f'MAD {out["mad"]:.4f} px')
    for label, (col, edges) in bins.items():
        cells = []
        for lo, hi in zip(edges[:-1], edges[1:]):
            s = r[(r[:, col] >= lo) & (r[:, col] < hi), 0]
            if len(s):
                cells.append({'lo': lo, 'hi': hi, 'share': len(s) / len(r), 'mean': s.mean(),
                              'median': float(np.median(s))})
        out['bins'][label] = cells
        print(f'  {label}: ' + '; '.join(f'[{c["lo"]:g}, {c["hi"]:g}) {100 * c["share"]:.1f} % {c["mean"]:+.4f}'
                                          for c in cells))
    report['matchers'][name] = out
if args.rows:
    np.save(args.rows, {name: np.array(r) for name, r in rows.items()}, allow_pickle=True)
if args.json:
    with open(args.json, 'w') as f:
        json.dump(report, f, indent=1)
