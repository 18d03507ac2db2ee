#!/usr/bin/python3
"""Which mechanism flagged the static observations of an idy run, and on what kind of corners.

Usage: scripts/analysis/static_flag_causes.py OBS.csv [DATASET]
OBS.csv is `idyvins run --dump-observations` of an idy run. Counts the observations of every
flagged track that lies wholly on static surfaces (the run summary's static share also counts the
static observations of tracks partly on moving objects) by the first reason the track was
flagged: lost-corner test, d_s elimination, stereo motion test, candidate or outlier confirmed.
With DATASET (the undistorted render the run read; Debian python3 with numpy, yaml, cv2) it also
prints, per cause and for the tracks never flagged, how edge-like the corners are (λ_min / λ_max
of the 15 x 15 px structure tensor of the left image where the track was first flagged, where it
started for the rest) and, over the static tracks seen at least 6 times, the share whose right
matches miss the point triangulated from the track's left positions and the ground-truth poses
by more than 2 px along u.
"""
import csv
import sys
from collections import Counter, defaultdict

if len(sys.argv) not in (2, 3):
    sys.exit(__doc__)
try:
    rows = list(csv.DictReader(open(sys.argv[1])))
except OSError as e:
    sys.exit(f'{sys.argv[1]}: {e}')
need = {'id', 't_ns', 'u', 'v', 'frontend_label', 'd_s_px2', 'credibility', 'stereo_chi2', 'on_moving',
        'confirmed_dynamic', 'outlier_removed'}
if not rows or not need <= set(rows[0]):
    sys.exit(f'{sys.argv[1]}: not an observation dump (expected the columns {", ".join(sorted(need))})')
tracks = defaultdict(list)
for r in rows:
    tracks[r['id']].append(r)


def cause_of(t):
    """(cause, observation where the track was first flagged) or None for a track never flagged."""
    el = [r for r in t if r['frontend_label'] == 'eliminated']
    if el:
        first = el[0]
        if len(t) == 1:
            return 'lost-corner test', first
        if float(first['d_s_px2'] or 0) * float(first['credibility'] or 1) > 4:
            return 'd_s elimination', first
        if float(first['stereo_chi2']) > 18.47:
            return 'stereo test', first
        return 'eliminated, other', first
    if any(r['confirmed_dynamic'] == '1' for r in t):
        why = 'outlier confirmed' if any(r['outlier_removed'] == '1' for r in t) else 'candidate confirmed'
        return why, t[-1]
    return None


counts, examples = Counter(), defaultdict(list)
n_static = sum(r['on_moving'] == '0' for r in rows)
for t in tracks.values():
    if any(r['on_moving'] == '1' for r in t):
        continue  # only tracks wholly on static surfaces
    c = cause_of(t)
    if c:
        counts[c[0]] += len(t)
    examples[c[0] if c else 'never flagged'].append((t, c[1] if c else t[0]))
flagged = sum(counts.values())
print(f'static observations {n_static}, of wholly static tracks flagged {flagged} ({100 * flagged / max(n_static, 1):.2f} %)')
for k, v in counts.most_common():
    print(f'  {k}: {v} ({100 * v / max(n_static, 1):.2f} %)')
if len(sys.argv) == 2:
    sys.exit(0)

import cv2  # noqa: E402 (only with DATASET)
import numpy as np  # noqa: E402

from sim_geometry import Rig  # noqa: E402

ds = sys.argv[2]
try:
    rig = Rig(ds)
except (OSError, KeyError) as e:
    sys.exit(f'{ds}: not a render with config/ and ground truth ({e})')


def isotropy(r):
    img = cv2.imread(f'{ds}/mav0/cam0/data/{r["t_ns"]}.png', cv2.IMREAD_GRAYSCALE)
    if img is None:
        sys.exit(f'{ds}/mav0/cam0/data/{r["t_ns"]}.png: not readable')
    u, v = round(float(r['u'])), round(float(r['v']))
    p = img[v - 8:v + 9, u - 8:u + 9].astype(float)
    if p.shape != (17, 17):
        return None
    gu, gv = 0.5 * (p[1:-1, 2:] - p[1:-1, :-2]), 0.5 * (p[2:, 1:-1] - p[:-2, 1:-1])
    e = np.linalg.eigvalsh([[np.sum(gu * gu), np.sum(gu * gv)], [np.sum(gu * gv), np.sum(gv * gv)]])
    return e[0] / e[1] if e[1] > 0 else None


def right_miss(t):
    """Largest |found - predicted| right u of a track seen 6+ times (None: shorter or no right match)."""
    if len(t) < 6:
        return None
    X = rig.triangulate([(int(r['t_ns']), (float(r['u']), float(r['v']))) for r in t])
    du = [abs(float(r['u_right']) - rig.project(1, int(r['t_ns']), X)[0][0]) for r in t if r.get('u_right')]
    return max(du) if du else None


rng = np.random.default_rng(1)
print('| tracks | count | λ_min / λ_max median | below 0.1 | seen 6+ times with a right match | right match > 2 px off |')
print('| --- | --- | --- | --- | --- | --- |')
for k, items in sorted(examples.items(), key=lambda kv: -len(kv[1])):
    if len(items) > 3000:  # the never-flagged tracks: a sample
        items = [items[i] for i in rng.choice(len(items), 3000, replace=False)]
    iso = np.array([x for x in (isotropy(r) for _, r in items) if x is not None])
    miss = np.array([x for x in (right_miss(t) for t, _ in items) if x is not None])
    print(f'| {k} | {len(items)} | {np.median(iso):.3f} | {100 * np.mean(iso < 0.1):.0f} % | {len(miss)} | '
          + (f'{100 * np.mean(miss > 2):.1f} % |' if len(miss) else '– |'))
