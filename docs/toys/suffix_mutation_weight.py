"""The contribution-weight update of a Metropolis-Hastings mutation of a resampled sample
(docs/guide/decorrelation.md, section 2), on a 2-D primary sample space u = (u1: prefix, u2: suffix)
with two colour channels and p_hat = their mean.

    python docs/toys/suffix_mutation_weight.py    # numpy only, about 20 s

(X, W) comes from RIS over 4 uniform candidates. A mutation proposes fresh suffix numbers,
accepts with min(1, p_hat(Y) / p_hat(X)) and sets W_Y = W_X p_hat(X) / p_hat(Y); a state "has
a reconnection vertex" when u1 < 0.7 and u2 < 0.8 (the lobe at z is decided by a suffix number).
Printed: the estimate of each channel and its z against the exact integral, for no mutation, two
mutations that keep the reconnection class (unbiased), two that do not (biased in colour), and
mutations switched on by W or by the sample itself (biased).
"""
import numpy as np
rng = np.random.default_rng(3); N = 4_000_000
def F(u1, u2):
    Fr = 0.2 + 4*u1*u2 + 3*(u2 > 0.9)
    Fg = (2 - u2)*(1 + 2*(u1 < 0.3))
    return Fr, Fg
p = lambda u1, u2: 0.5*sum(F(u1, u2))
g = (np.arange(4000) + 0.5)/4000
G1, G2 = np.meshgrid(g, g, indexing='ij')
Ir, Ig = (c.mean() for c in F(G1, G2))
def initial():
    U1, U2 = rng.random((4, N)), rng.random((4, N))
    w = p(U1, U2)/4
    cs = np.cumsum(w, 0); pick = (rng.random(N)*cs[-1] > cs).sum(0)
    u1, u2 = U1[pick, np.arange(N)], U2[pick, np.arange(N)]
    return u1, u2, cs[-1]/p(u1, u2)
has_rc = lambda u1, u2: (u1 < 0.7) & (u2 < 0.8)
def mutate(u1, u2, W, enforce=True, active=None):
    v2 = rng.random(N)
    px, py = p(u1, u2), p(u1, v2)
    ok = has_rc(u1, u2) & (rng.random(N) < np.minimum(1, py/px))
    if enforce: ok &= has_rc(u1, v2)
    if active is not None: ok &= active
    return u1, np.where(ok, v2, u2), np.where(ok, W*px/py, W)
def report(name, u1, u2, W):
    Fr, Fg = F(u1, u2)
    er, eg = Fr*W, Fg*W
    zr = (er.mean()-Ir)/(er.std()/np.sqrt(N)); zg = (eg.mean()-Ig)/(eg.std()/np.sqrt(N))
    print(f"{name:38s} R {er.mean():.4f} (z={zr:+6.1f})  G {eg.mean():.4f} (z={zg:+6.1f})   exact {Ir:.4f} {Ig:.4f}")
u1, u2, W = initial(); report("RIS, no mutation", u1, u2, W)
a = mutate(u1, u2, W); a = mutate(*a); report("2 suffix mutations, rc class kept", *a)
b = mutate(u1, u2, W, enforce=False); b = mutate(*b, enforce=False); report("2 mutations, class not enforced", *b)
c = mutate(u1, u2, W, active=W > np.quantile(W, 0.8)); report("1 mutation only where W > q80(W)", *c)
d = mutate(u1, u2, W, active=u2 < 0.3); report("1 mutation only where u2 < 0.3", *d)
