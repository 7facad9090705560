# probe_pnp_nees --dump FILE: lag 1, 2, 5, 10, 30 autocorrelations of the
# whitened PnP errors, per camera, images in stamp order. Usage: python3 pnp_autocorrelation.py FILE
import sys, numpy as np
from collections import defaultdict
g=defaultdict(list)
for l in open(sys.argv[1]):
    x=l.strip().split(',')
    seed=int(x[0]); cam=x[1]; t=int(x[2])
    e=np.array(list(map(float,x[4:10]))); C=np.array(list(map(float,x[10:46]))).reshape(6,6)
    g[(seed,cam)].append((t,e,C))
for cam in sorted(set(c for s,c in g)):
    acs=defaultdict(list); nees=[]; agg=[]
    for (seed,c),items in g.items():
        if c!=cam: continue
        items=sorted(items,key=lambda x:x[0])
        W=np.array([np.linalg.solve(np.linalg.cholesky(C),e) for t,e,C in items])
        nees+=list((W**2).sum(1))
        for lag in (1,2,5,10,30):
            acs[lag].append([np.corrcoef(W[:-lag,i],W[lag:,i])[0,1] for i in range(6)])
    print(cam, len(nees),'images, per-image NEES %.2f'%np.mean(nees))
    for lag in acs: print('   lag',lag, np.round(np.mean(acs[lag],axis=0),2))
