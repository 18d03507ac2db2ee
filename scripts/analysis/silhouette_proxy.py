#!/usr/bin/python3
"""Proxy for silhouette / occlusion: are the static tracks the stereo motion test eliminated next to a vehicle?

Usage: scripts/analysis/silhouette_proxy.py OBS.csv DATASET   (Debian python3 with numpy, matplotlib)
For each static track (no observation on a vehicle) eliminated by the stereo test, looks
for vehicle pixels in the cam1 / cam0 masks in a 7-row band up to W px left of the corner
at the elimination frame, against a random sample of other static tracked observations.
"""
import csv, sys, collections, numpy as np, random
import matplotlib.image as mpimg
if len(sys.argv) != 3:
    sys.exit('usage: silhouette_proxy.py OBS.csv DATASET')
rows=list(csv.DictReader(open(sys.argv[1]))); ds=sys.argv[2]
trk=collections.defaultdict(list)
for r in rows: trk[r['id']].append(r)
ev=[]
for tid,t in trk.items():
    el=[r for r in t if r['frontend_label']=='eliminated']
    if not el or len(t)==1: continue
    if any(r['on_moving']=='1' for r in t): continue
    f=el[0]
    if float(f['stereo_chi2'])>18.47: ev.append(f)
cache={}
def mask(cam,t):
    k=(cam,t)
    if k not in cache: cache[k]=mpimg.imread(f'{ds}/mav0/{cam}/mask/{t}.png')>0
    return cache[k]
def near(r,cam,w):
    m=mask(cam,r['t_ns']); u=int(float(r['u'])); v=int(float(r['v']))
    return m[max(v-3,0):v+4, max(u-w,0):u+4].any()
random.seed(1)
st=[r for r in rows if r['on_moving']=='0' and r['frontend_label']!='eliminated' and int(r['track_length'])>1]
sample=random.sample(st,min(len(ev)*3,len(st)))
for w in [30,80]:
    a=np.mean([near(r,'cam1',w) for r in ev]); b=np.mean([near(r,'cam1',w) for r in sample])
    a0=np.mean([near(r,'cam0',w) for r in ev]); b0=np.mean([near(r,'cam0',w) for r in sample])
    print('window %d px left of u: vehicle in cam1 mask: stereo-eliminated static %.2f vs other static %.2f; cam0 %.2f vs %.2f (n=%d)'%(w,a,b,a0,b0,len(ev)))
