# I and L lines of bench_consistency --per-seed FILE (see its comment lines):
# per-image NEES at the truth and the share above the 99.9 % gate; the
# aggregate NEES of the information-weighted mean error over a seed's images
# in three frames; lag autocorrelations of the whitened errors; and the L
# lines' means (linearized NEES, covariance against the reported one, the
# Newey-West variants). Usage: python3 aggregate_at_truth.py FILE...
import csv, sys, numpy as np
from collections import defaultdict
files=sys.argv[1:]
rows=[]
est={}
for fn in files:
    for l in open(fn):
        if l.startswith('I,'): rows.append(l.strip().split(','))
        elif l[0].isdigit():
            x=l.split(','); est.setdefault(x[1]+' '+x[2],[]).append(float(x[3]))
for k,v in sorted(est.items()): print(k, np.mean(v).round(2), len(v))
g=defaultdict(list)
for r in rows:
    seed=int(r[1]); cam=r[3]
    e=np.array(list(map(float,r[7:13]))); C=np.array(list(map(float,r[13:49]))).reshape(6,6)
    R=np.array(list(map(float,r[49:76]))).reshape(3,3,3)
    t=int(r[76])
    g[(seed,cam)].append((t,e,C,R))
def agg(items, frame):
    I=np.zeros((6,6)); b=np.zeros(6)
    for t,e,C,R in items:
        if frame=='marker': A=np.eye(6)
        else:
            Rx=R[0] if frame=='base' else R[1]
            A=np.zeros((6,6)); A[:3,:3]=Rx; A[3:,3:]=Rx
        Ci=np.linalg.inv(A@C@A.T); I+=Ci; b+=Ci@(A@e)
    m=np.linalg.solve(I,b); return m@I@m
for cam in sorted(set(c for s,c in g)):
    n=[float(r[4]) for r in rows if r[3]==cam]
    print('%s: %d images, per-image NEES at the truth %.2f, above 22.46: %.2f %%'%(cam,len(n),np.mean(n),100*np.mean(np.array(n)>22.46)))
Ls=defaultdict(list)
for fn in files:
    for l in open(fn):
        if l.startswith('L,'):
            x=l.strip().split(','); Ls[x[2]].append(list(map(float,x[3:])))
for cam,v in Ls.items():
    v=np.array(v)
    print('%s L lines (%d): linearized NEES %.2f, sqrt(tr P/tr reported) %.3f, rel. diff %.3f; sandwich NEES lags 0,5,10,20,40:'%(cam,len(v),v[:,0].mean(),v[:,1].mean(),v[:,2].mean()),
          np.round(v[:,3::2].mean(0),2),'sqrt trace ratio:',np.round(v[:,4::2].mean(0),2))
for frame in ['marker','base','camera']:
    res=defaultdict(list)
    for (seed,cam),items in g.items(): res[cam].append(agg(items,frame))
    print('aggregate NEES of the weighted mean error, frame',frame, {c:np.round(np.mean(v),2) for c,v in res.items()})
for cam in sorted(set(c for s,c in g)):
    acs=[[] for _ in range(5)]
    for (seed,c),items in g.items():
        if c!=cam: continue
        items=sorted(items,key=lambda x:x[0])
        W=np.array([np.linalg.solve(np.linalg.cholesky(C),e) for t,e,C,R in items])
        for lag in range(1,6):
            acs[lag-1].append([np.corrcoef(W[:-lag,i],W[lag:,i])[0,1] for i in range(6)])
    for lag in range(1,6): print(cam,'lag',lag,'autocorr of whitened e', np.round(np.mean(acs[lag-1],axis=0),2))
