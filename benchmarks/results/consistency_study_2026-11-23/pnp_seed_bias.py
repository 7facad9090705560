# probe_pnp_nees --dump FILE: per seed and camera, the information-weighted
# mean PnP error over the seed's images in camera axes, its standard error,
# and its NEES (6 when the images' errors are independent). Usage: python3 pnp_seed_bias.py FILE
import sys, numpy as np
from collections import defaultdict
g=defaultdict(list)
for l in open(sys.argv[1]):
    x=l.strip().split(',')
    seed=int(x[0]); cam=x[1]
    e=np.array(list(map(float,x[4:10]))); C=np.array(list(map(float,x[10:46]))).reshape(6,6); R=np.array(list(map(float,x[46:55]))).reshape(3,3)
    A=np.zeros((6,6)); A[:3,:3]=R; A[3:,3:]=R
    g[(seed,cam)].append((A@e, A@C@A.T))
res=defaultdict(list)
for (seed,cam),items in sorted(g.items()):
    I=sum(np.linalg.inv(C) for e,C in items); b=sum(np.linalg.inv(C)@e for e,C in items)
    m=np.linalg.solve(I,b); n=m@I@m
    sd=np.sqrt(np.diag(np.linalg.inv(I)))
    res[cam].append(n)
    print(seed,cam,len(items),'seed-mean error (cam axes, mrad / mm):',np.round(m[:3]*1e3,3),np.round(m[3:]*1e3,3),' its s.e.:',np.round(sd[:3]*1e3,3),np.round(sd[3:]*1e3,3),' NEES %.1f'%n)
for c,v in res.items(): print(c,'mean aggregate NEES over seeds %.1f (6 if no per-seed bias)'%np.mean(v))
