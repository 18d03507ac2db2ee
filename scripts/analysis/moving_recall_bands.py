#!/usr/bin/python3
"""Which moving observations an idy run misses: single-frame corners, far points, tracks without stereo.

Usage: scripts/analysis/moving_recall_bands.py OBS.csv [OBS.csv ...]
OBS.csv is `idyvins run --dump-observations`. A track is moving when at least half of its
observations lie on a moving object (the masks); it is flagged when eliminated at any
observation or confirmed dynamic (as the run summary counts). Per file, the moving
observations and the share flagged by band:
  seen once        tracks of one observation (judged only by the lost-corner test, which
                   needs a right match), with and without a right match;
  near / mid / far tracks seen at least twice, by the median stereo depth of the stereo
                   motion test (< 20 m, 20-40 m, >= 40 m);
  no stereo        tracks seen at least twice that the stereo test never measured.
The last column is the share of the static observations in single-frame corners that
were not flagged (what a looser test of single-frame corners would risk). Standard library only.
"""
import collections
import csv
import statistics
import sys

BANDS = ['seen once, right', 'seen once, no right', 'near <20 m', 'mid 20-40 m', 'far >=40 m', 'no stereo']


def band(obs):
    if len(obs) == 1:
        return BANDS[0] if obs[0]['u_right'] else BANDS[1]
    depths = [float(o['stereo_depth_m']) for o in obs if float(o['stereo_depth_m']) > 0]
    if not depths:
        return BANDS[5]
    d = statistics.median(depths)
    return BANDS[2] if d < 20 else BANDS[3] if d < 40 else BANDS[4]


def summarize(path):
    tracks = collections.defaultdict(list)
    for r in csv.DictReader(open(path)):
        tracks[r['id']].append(r)
    moving, flagged = collections.Counter(), collections.Counter()
    static_total = static_once_unflagged = 0
    for obs in tracks.values():
        on_moving = sum(o['on_moving'] == '1' for o in obs)
        is_flagged = any(o['frontend_label'] == 'eliminated' or o['confirmed_dynamic'] == '1' for o in obs)
        if 2 * on_moving < len(obs):
            static_total += len(obs)
            static_once_unflagged += len(obs) == 1 and not is_flagged
            continue
        b = band(obs)
        moving[b] += on_moving
        flagged[b] += on_moving if is_flagged else 0
    return moving, flagged, static_once_unflagged / max(static_total, 1)


def main():
    if len(sys.argv) < 2:
        sys.exit(__doc__)
    print('| run | moving obs | flagged | ' + ' | '.join(BANDS) + ' | static seen once, unflagged |')
    print('|' + ' --- |' * (len(BANDS) + 4))
    for path in sys.argv[1:]:
        moving, flagged, static_once = summarize(path)
        total = sum(moving.values())
        cells = [f'{moving[b] / max(total, 1):.0%} of obs, {flagged[b] / moving[b]:.0%} flagged' if moving[b] else '-'
                 for b in BANDS]
        print(f'| {path} | {total} | {sum(flagged.values()) / max(total, 1):.1%} | ' + ' | '.join(cells) +
              f' | {static_once:.1%} |')


if __name__ == '__main__':
    main()
