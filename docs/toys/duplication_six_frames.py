"""Duplication-scaled history confidence over six frames of temporal and spatial reuse
(docs/guide/decorrelation.md, section 1).

    python docs/toys/duplication_six_frames.py    # numpy only, about 10 s

Two pixels A, B on [0, 1] with different integrands (each integrates to 1.9), identity shifts,
target = integrand, one uniform candidate a frame, temporal Talbot MIS (history = the same pixel,
M capped at 20) and one pairwise spatial pass (each the other's neighbour). d = 2 when A and B
held the same sample last frame, and the history's confidence is multiplied by g(d). Printed
per frame: each pixel's mean and its z against 1.9, for g(2) = 1, 1/2, 0 driven by the real
duplication ("dup") and by an independent coin at a similar rate ("coin"). The frames share their
random numbers, so one run's z repeats from frame to frame.
"""
import numpy as np, sys
fA = lambda x: 1 + 9*(x < 0.1)
fB = lambda x: 1 + 9*((x > 0.05) & (x < 0.15))
IA, IB = 1.9, 1.9
CAP, T, N = 20.0, 6, 1_000_000

def run(g2, mode, rng):
    f = [fA, fB]
    hx = [None, None]; hW = [None, None]; hM = [None, None]; hs = [None, None]
    out = np.zeros((T, 2))
    se = np.zeros((T, 2))
    pdup = 0.3
    for t in range(T):
        xs, Ws, Ms, ss = [], [], [], []
        if t > 0:
            dup = hs[0] == hs[1]
            if mode == 'coin':      # same marginal rate, independent of the samples
                dup = rng.random(N) < pdup
            elif mode == 'dup':
                pdup = dup.mean()
            g = np.where(dup, g2, 1.0)
        for p in range(2):
            x = rng.random(N); W = np.ones(N); M = np.ones(N); s = np.full(N, 2*t + p)
            if t > 0:
                Mq = np.minimum(hM[p], CAP * M) * g
                wc = M/(M+Mq) * f[p](x) * W           # Talbot: same target -> constant weights
                wq = Mq/(M+Mq) * f[p](hx[p]) * hW[p]
                ws = wc + wq
                pickq = rng.random(N) * ws < wq
                x = np.where(pickq, hx[p], x); s = np.where(pickq, hs[p], s)
                W = ws / f[p](x); M = M + Mq
            xs.append(x); Ws.append(W); Ms.append(M); ss.append(s)
        nx, nW, nM, ns = [], [], [], []
        for p in range(2):       # spatial, pairwise MIS, k = 1, V = 1
            c, n = p, 1 - p
            fc, fn = f[c], f[n]
            y = xs[n]
            di, dc = fn(y)*Ms[n], fc(y)*Ms[c]
            wi = di/(di+dc) * fc(y) * Ws[n]
            dcx, dix = fc(xs[c])*Ms[c], fn(xs[c])*Ms[n]
            wc = (1 + dcx/(dix+dcx)) * fc(xs[c]) * Ws[c]
            ws = wi + wc
            pickn = rng.random(N) * ws < wi
            x = np.where(pickn, y, xs[c]); s = np.where(pickn, ss[n], ss[c])
            W = ws / fc(x) / 2
            nx.append(x); nW.append(W); nM.append(Ms[c] + Ms[n]); ns.append(s)
            est = fc(x) * W
            out[t, p] = est.mean(); se[t, p] = est.std() / np.sqrt(N)
        hx, hW, hM, hs = nx, nW, nM, ns
    return out, se, pdup

for g2, mode in [(1.0, 'dup'), (0.5, 'dup'), (0.0, 'dup'), (0.5, 'coin'), (0.0, 'coin')]:
    rng = np.random.default_rng(1)
    o, s, pd = run(g2, mode, rng)
    zA = (o[:, 0] - IA)/s[:, 0]; zB = (o[:, 1] - IB)/s[:, 1]
    print(f"g(2)={g2} {mode:4s} P(dup)~{pd:.3f}")
    for t in range(T):
        print(f"  t={t} A {o[t,0]:.4f} (z={zA[t]:+6.1f})  B {o[t,1]:.4f} (z={zB[t]:+6.1f})")
