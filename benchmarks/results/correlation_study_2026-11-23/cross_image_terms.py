# I lines of bench_consistency --per-seed FILE (see its comment lines): per
# seed and camera, the information-weighted mean of the images' errors at the
# truth in camera axes (the F1 correction, the mount aside) and its NEES
# ("obs"), split into what independent images would give (trace of
# I^-1 sum g_i g_i^T, "indep") and the cross-image terms g_i g_j^T by lag in
# images (time order): lags 1-5, 6-20, 21-60 and beyond. obs = indep + the lag
# columns. Usage: python3 cross_image_terms.py FILE...
import sys, numpy as np
from collections import defaultdict


def load(files):
    """(file, seed, camera) -> [(stamp, e, C, R_base_marker / R_cam_marker / R_link_marker)] from I lines;
    weights(items) -> the information I, per-image W and errors in camera axes."""
    g = defaultdict(list)
    for fn in files:
        for l in open(fn):
            if not l.startswith('I,'):
                continue
            r = l.strip().split(',')
            e = np.array(list(map(float, r[7:13])))
            C = np.array(list(map(float, r[13:49]))).reshape(6, 6)
            R = np.array(list(map(float, r[49:76]))).reshape(3, 3, 3)
            g[(fn, int(r[1]), r[3])].append((int(r[76]), e, C, R))
    for items in g.values():
        items.sort(key=lambda x: x[0])
    return g


def camera_axes(items):
    """Information I, and per image W and e in camera axes (marker -> camera rotation)."""
    I = np.zeros((6, 6)); Ws = []; es = []
    for t, e, C, R in items:
        A = np.zeros((6, 6)); A[:3, :3] = R[1]; A[3:, 3:] = R[1]
        W = np.linalg.inv(A @ C @ A.T); I += W; Ws.append(W); es.append(A @ e)
    return I, Ws, es


def main():
    bands = [(1, 5), (6, 20), (21, 60), (61, 10**6)]
    out = defaultdict(lambda: defaultdict(list))
    for (fn, seed, cam), items in load(sys.argv[1:]).items():
        I, Ws, es = camera_axes(items)
        gs = np.array([W @ e for W, e in zip(Ws, es)])
        m = np.linalg.solve(I, gs.sum(0)); Ii = np.linalg.inv(I)
        o = out[cam]
        o['obs'].append(m @ I @ m)
        o['indep'].append(np.trace(Ii @ (gs.T @ gs)))
        for lo, hi in bands:
            S = np.zeros((6, 6))
            for lag in range(lo, min(hi, len(gs) - 1) + 1):
                X = gs[:-lag].T @ gs[lag:]; S += X + X.T
            o['lags %d-%s' % (lo, hi if hi < 10**6 else 'end')].append(np.trace(Ii @ S))
    for cam, o in sorted(out.items()):
        n = len(o['obs'])
        print('%s, %d seeds: NEES %.2f (s.e. %.2f) = independent %.2f' % (cam, n, np.mean(o['obs']), np.std(o['obs']) / np.sqrt(n), np.mean(o['indep'])),
              ' '.join('+ %s %.2f' % (k, np.mean(v)) for k, v in o.items() if k.startswith('lags')))


if __name__ == '__main__':
    main()
