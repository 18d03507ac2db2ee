#!/usr/bin/python3
"""Which mechanism flagged the static observations of an idy run.

Usage: scripts/analysis/static_flag_causes.py OBS.csv   (from `idyvins run --dump-observations OBS.csv`)
Counts every static observation of a flagged track (as the run summary does) by the
first reason the track was flagged: lost-corner test, d_s elimination, stereo motion test,
candidate or outlier confirmed dynamic.
"""
import csv, sys, collections
if len(sys.argv) != 2:
    sys.exit('usage: static_flag_causes.py OBS.csv')
rows = list(csv.DictReader(open(sys.argv[1])))
trk = collections.defaultdict(list)
for r in rows: trk[r['id']].append(r)
st = [r for r in rows if r['on_moving']=='0']
cause = collections.Counter(); 
for tid,t in trk.items():
    el=[r for r in t if r['frontend_label']=='eliminated']
    conf=any(r['confirmed_dynamic']=='1' for r in t)
    if not el and not conf: continue
    nst=sum(r['on_moving']=='0' for r in t)
    if nst==0: continue
    if el:
        first=el[0]
        if len(t)==1: c='lost-corner'
        elif float(first['d_s_px2'] or 0)*float(first['credibility'] or 1)>4 and True: c='d_s elimination'
        elif float(first['stereo_chi2'])>18.47: c='stereo test'
        else: c='eliminated other'
    else:
        c='outlier removed->confirmed' if any(r['outlier_removed']=='1' for r in t) else 'candidate confirmed'
    # majority moving? ghost of mask boundary
    mov=sum(r['on_moving']=='1' for r in t)
    cause[(c,'track partly on moving' if mov else 'static track')]+=nst
tot=len(st); print('static obs',tot,'flagged',sum(cause.values()), '%.2f%%'%(100*sum(cause.values())/tot))
for k,v in sorted(cause.items(), key=lambda x:-x[1]): print(k, v, '%.2f%%'%(100*v/tot))
