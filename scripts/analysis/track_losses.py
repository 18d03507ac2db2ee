#!/usr/bin/python3
"""Why tracks end, per frame, summed over sets of runs.

Usage: scripts/analysis/track_losses.py LABEL=RUN_DIR[,RUN_DIR...] [LABEL=...]
Each RUN_DIR is an `idyvins run` output folder (its stats.json). Prints one markdown row per
label: runs, features per frame, tracks of the previous frame that ended per frame (and as a
share of the features), then per reason (stats.json's `lost_tracks`: KLT did not converge,
forward-backward check, first-patch alignment, image border, min_dist pruning).
"""
import json
import sys

REASONS = ('klt', 'backward', 'alignment', 'border', 'pruned')

if len(sys.argv) < 2 or any('=' not in a for a in sys.argv[1:]):
    sys.exit(__doc__)
rows = []
for arg in sys.argv[1:]:
    label, dirs = arg.split('=', 1)
    frames = features = 0
    lost = dict.fromkeys(REASONS, 0)
    dirs = dirs.split(',')
    for d in dirs:
        try:
            stats = json.load(open(f'{d}/stats.json'))
        except (OSError, json.JSONDecodeError) as e:
            sys.exit(f'{d}/stats.json: {e}')
        for f in stats['frames']:
            frames += 1
            features += f.get('features', 0)
            for k, v in f.get('lost_tracks', {}).items():
                lost[k] += v
    if frames == 0 or features == 0:
        sys.exit(f'{label}: no frames with features')
    total = sum(lost.values())
    rows.append(f'| {label} | {len(dirs)} | {features / frames:.0f} | {total / frames:.1f} ({100 * total / features:.0f} %) | '
                + ' | '.join(f'{lost[k] / frames:.1f}' for k in REASONS) + ' |')
print('| runs | count | features per frame | tracks ended per frame | ' + ' | '.join(REASONS) + ' |')
print('| --- ' * (4 + len(REASONS)) + '|')
print('\n'.join(rows))
