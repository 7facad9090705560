# R lines of bench_consistency --resample-encoders 1 --per-seed FILE: per F1
# camera, the NEES of the linearized correction from all errors, from the
# kinematic errors alone and from the PnP errors alone, with what the model
# expects of the last two. Usage: python3 split_at_truth.py FILE
import sys, numpy as np
from collections import defaultdict
R = defaultdict(list); est = defaultdict(list)
for l in open(sys.argv[1]):
    x = l.strip().split(',')
    if x[0] == 'R': R[x[2]].append(list(map(float, x[3:8])))
    elif x[0].isdigit(): est[x[1] + ' ' + x[2]].append(float(x[3]))
for c, v in R.items():
    m = np.array(v).mean(0)
    print('%s %d seeds: full %.2f | kinematic %.2f (model %.2f, ratio %.2f) | PnP %.2f (model %.2f, ratio %.2f)'
          % (c, len(v), m[0], m[1], m[3], m[1] / m[3], m[2], m[4], m[2] / m[4]))
print('estimates, mean NEES:', {k: round(float(np.mean(v)), 2) for k, v in sorted(est.items())})
