"""Why a temporal history's confidence may not depend on how many pixels hold its sample
(docs/guide/decorrelation.md, section 1): the smallest case, solved exactly with fractions and checked
by Monte Carlo.

    python docs/toys/duplication_confidence_bias.py     # numpy only, about 10 s

Two pixels A and B share the integrand f (9 on [0, 0.1), 1 elsewhere; integral 1.8), identity
shifts, target p_hat = f. Frame 0: one uniform candidate each (W = 1, M = 1) and one pairwise
spatial pass between A and B. Frame 1 at A: a fresh candidate (M = 1) and the history (M = 2,
under the cap) by Talbot MIS, the history's confidence multiplied by g(d), d = 2 when A and B
ended frame 0 with the same sample. g = 1 is unbiased; g(2) = 1/2 reads 1.9% low, g(2) = 0 7.6%.
"""
from fractions import Fraction as Fr
import numpy as np
a, h = Fr(1, 10), Fr(9)
I = a*h + (1-a)
def exact(g2):
    E = Fr(0)
    for fa, pa in ((h, a), (1, 1-a)):
        for fb, pb in ((h, a), (1, 1-a)):
            fw = (fb + 3*fa)/4                                  # f(Y)W of A after spatial (any selection)
            pdup = 3*(fa*fa + fb*fb)/((fb + 3*fa)*(fa + 3*fb))  # both end with the same sample
            for dup, pd in ((True, pdup), (False, 1-pdup)):
                Mq = 2*(g2 if dup else 1)
                mq = Mq/(1+Mq)
                E += pa*pb*pd*((1-mq)*I + mq*fw)                # canonical independent of G
    return E
rng = np.random.default_rng(7); N = 4_000_000
f = lambda x: np.where(x < float(a), float(h), 1.0)
def mc(g2):
    xa, xb = rng.random(N), rng.random(N)
    fa, fb = f(xa), f(xb)
    # spatial at A: neighbour weight (1/2) f(xb), canonical (3/2) f(xa); at B symmetric
    pickA = rng.random(N)*(0.5*fb + 1.5*fa) < 0.5*fb
    pickB = rng.random(N)*(0.5*fa + 1.5*fb) < 0.5*fa
    yA = np.where(pickA, xb, xa); yB = np.where(pickB, xa, xb)
    WA = (0.5*fb + 1.5*fa)/f(yA)/2
    dup = yA == yB
    Mq = 2*np.where(dup, g2, 1.0)
    xc = rng.random(N)
    wc = f(xc)/(1+Mq); wq = Mq/(1+Mq)*f(yA)*WA
    est = wc + wq                                               # f(Y)W = w_sum since p_hat = f
    return est.mean(), est.std()/np.sqrt(N)
print("I =", I, float(I))
for g2 in (Fr(1), Fr(1, 2), Fr(0)):
    e = exact(g2); m, s = mc(float(g2))
    print(f"g(2)={g2}: exact E={float(e):.5f} bias={float(e-I):+.5f} ({float((e-I)/I)*100:+.2f}%)  MC {m:.5f} +- {s:.5f}")
