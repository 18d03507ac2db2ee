#!/usr/bin/python3
"""Where the missed moving observations sit: on a vehicle's silhouette or on its body.

Usage: scripts/analysis/moving_misses.py OBS.csv DATASET [RADIUS]   (Debian python3 with numpy, matplotlib)
OBS.csv is `idyvins run --dump-observations` of a rendered DATASET (its mav0/cam0/mask PNGs).
Each tracked observation on a moving object is a silhouette observation when a pixel of
another object or of the static scene lies within RADIUS px (default 3) in the mask, a
body observation otherwise. Prints, for both, how many there are, the share flagged
(eliminated in the front end or confirmed dynamic) and what the missed ones are: early
observations of tracks flagged later, tracks that live at most two frames, tracks never flagged.
"""
import csv
import os
import sys

import matplotlib.image as mpimg
import numpy as np

if len(sys.argv) not in (3, 4):
    sys.exit(__doc__)
dump, ds = sys.argv[1], sys.argv[2]
radius = int(sys.argv[3]) if len(sys.argv) == 4 else 3
rows = [r for r in csv.DictReader(open(dump)) if r['on_moving'] == '1']
obs, cur_t, mask = [], None, None
for r in rows:  # the dump is in time order
    if r['t_ns'] != cur_t:
        cur_t = r['t_ns']
        mask = (mpimg.imread(os.path.join(ds, 'mav0/cam0/mask', cur_t + '.png')) * 255).round().astype(np.uint8)
    u, v = int(round(float(r['u']))), int(round(float(r['v'])))
    window = mask[max(0, v - radius):v + radius + 1, max(0, u - radius):u + radius + 1]
    flagged = r['frontend_label'] == 'eliminated' or r['confirmed_dynamic'] != '0'
    obs.append((bool((window != mask[v, u]).any()), flagged, r['id'], int(r['track_length'])))
flagged_ids = {i for _, fl, i, _ in obs if fl}
longest = {}
for _, _, i, tl in obs:
    longest[i] = max(longest.get(i, 0), tl)
missed_all = sum(1 for o in obs if not o[1])
print(f'{len(obs)} moving observations, {missed_all} missed ({100 * missed_all / max(len(obs), 1):.1f} %), radius {radius} px')
for name, kind in (('silhouette', True), ('body', False)):
    part = [o for o in obs if o[0] == kind]
    missed = [o for o in part if not o[1]]
    later = sum(1 for o in missed if o[2] in flagged_ids)
    short = sum(1 for o in missed if o[2] not in flagged_ids and longest[o[2]] <= 2)
    never = len(missed) - later - short
    print(f'{name}: {len(part)} ({100 * len(part) / max(len(obs), 1):.1f} %), flagged '
          f'{100 * (len(part) - len(missed)) / max(len(part), 1):.1f} %, missed {len(missed)} '
          f'({100 * len(missed) / max(missed_all, 1):.1f} % of the missed): {later} early in tracks flagged later, '
          f'{short} in tracks of <= 2 frames, {never} in longer tracks never flagged')
