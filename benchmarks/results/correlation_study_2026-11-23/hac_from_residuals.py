# Can the correlation be estimated from a calibration's own residuals? Same
# input and weighted mean as cross_image_terms.py, but the scores use the
# residuals (error minus the weighted mean), as a solver would have them, in
# a Bartlett-kernel long-run variance with bandwidth L. k = tr(I^-1 S_L) / 6
# would scale the covariance; the NEES after scaling by max(1, k) is printed.
# Usage: python3 hac_from_residuals.py FILE...
import sys, numpy as np
from collections import defaultdict
from cross_image_terms import load, camera_axes
Ls = [0, 10, 20, 40, 80]
out = defaultdict(lambda: defaultdict(list))
for key, items in load(sys.argv[1:]).items():
    I, Ws, es = camera_axes(items)
    m = np.linalg.solve(I, sum(W @ e for W, e in zip(Ws, es))); Ii = np.linalg.inv(I)
    nees = m @ I @ m
    gs = np.array([W @ (e - m) for W, e in zip(Ws, es)])
    o = out[key[2]]; o['obs'].append(nees)
    for L in Ls:
        S = gs.T @ gs
        for lag in range(1, min(L, len(gs) - 1) + 1):
            X = gs[:-lag].T @ gs[lag:]; S += (1 - lag / (L + 1)) * (X + X.T)
        k = np.trace(Ii @ S) / 6
        o['k%d' % L].append(k); o['adj%d' % L].append(nees / max(1.0, k))
for cam, o in sorted(out.items()):
    print('%s, %d seeds: NEES %.2f' % (cam, len(o['obs']), np.mean(o['obs'])))
    for L in Ls:
        print('  bandwidth %2d: mean k %.3f (sd %.3f), NEES / max(1, k) %.2f' % (L, np.mean(o['k%d' % L]), np.std(o['k%d' % L]), np.mean(o['adj%d' % L])))
