# R lines of bench_consistency --resample-encoders 1 --per-seed FILE: per F1
# camera, the NEES of the correction linearized at the truth from all image
# errors, from the kinematic errors alone and from the PnP errors alone, with
# what the model expects of the two parts (they should add up to "all"), of
# the kinematic floors and of the mount prior (which weigh the solve but draw
# no error in the simulation). Usage: python3 split_at_truth.py FILE
# (R lines of 5 numbers, from fae89d5, lack the floor and prior columns and
# count the floors in the kinematic model.)
import sys, numpy as np
from collections import defaultdict
R = defaultdict(list); est = defaultdict(list)
for l in open(sys.argv[1]):
    x = l.strip().split(',')
    if x[0] == 'R':
        v = list(map(float, x[3:10]))
        R[x[2]].append(v + [float('nan')] * (7 - len(v)))
    elif x[0].isdigit(): est[x[1] + ' ' + x[2]].append(float(x[3]))
for c, v in R.items():
    m = np.array(v).mean(0)
    print('%s %d seeds: all %.2f (model %.2f) | kinematic %.2f (model %.2f, ratio %.2f) | PnP %.2f (model %.2f, ratio %.2f)'
          ' | model floors %.2f, prior %.2f' % (c, len(v), m[0], m[3] + m[4], m[1], m[3], m[1] / m[3], m[2], m[4],
                                               m[2] / m[4], m[5], m[6]))
print('estimates, mean NEES:', {k: round(float(np.mean(v)), 2) for k, v in sorted(est.items())})
