# ---
# jupyter:
#   jupytext:
#     text_representation:
#       extension: .py
#       format_name: percent
#       format_version: '1.3'
#       jupytext_version: 1.19.7
#   kernelspec:
#     display_name: Python 3 (ipykernel)
#     language: python
#     name: python3
# ---

# %% [markdown]
# # RIS, reservoirs and ReSTIR DI
#
# This tutorial builds resampled importance sampling (RIS) on a one-dimensional integral, small
# enough to write in a few lines of numpy, checks that the renderer's own resampling code makes
# exactly the same choices, and then watches ReSTIR DI converge on a scene lit by 400 small lights.
#
# The theory is in [Resampled importance sampling](../../theory/ris/) and
# [Reservoirs and M-capping](../../theory/reservoirs/); symbols are those of the
# [notation page](../../theory/notation/): the target function $\hat p$, the running sum of
# resampling weights $w_\mathrm{sum}$, the unbiased contribution weight $W$, the confidence
# $M$ and MIS weights $m_i$.
#
# The notebook runs from `docs/tutorials/` in a checkout of the repository, with the project's
# virtual environment as its kernel.

# %%
import pathlib
import sys

import matplotlib.pyplot as plt
import numpy as np

# the repository's root (this notebook lives in docs/tutorials/): restir imports from there
ROOT = next(p for p in (pathlib.Path.cwd(), *pathlib.Path.cwd().parents) if (p / "restir" / "__init__.py").is_file())
sys.path.insert(0, str(ROOT))

import restir  # noqa: E402

rng = np.random.default_rng(11)

# %% [markdown]
# ## A one-dimensional integral
#
# The integrand $f$ lives on $[0, 1]$ and has a closed-form integral. Candidates come from the
# uniform density $p(x) = 1$, which knows nothing about $f$. The target function $\hat p$
# is a rougher version of $f$ without its $x^2$ term: RIS only needs
# $\hat p > 0$ wherever $f \ne 0$, and $\hat p$ need not be normalized.

# %%
def f(x):
    return 0.2 + x ** 2 + 3.0 * np.sin(5.0 * x) ** 2


def p_hat(x):
    return 0.3 + 3.0 * np.sin(5.0 * x) ** 2


I_EXACT = 0.2 + 1.0 / 3.0 + 3.0 * (0.5 - np.sin(10.0) / 20.0)

xs = np.linspace(0.0, 1.0, 400)
plt.figure(figsize=(6, 3))
plt.plot(xs, f(xs), label="f (integrand)")
plt.plot(xs, p_hat(xs), label=r"$\hat p$ (target)")
plt.axhline(1.0, color="grey", ls=":", label="p (source, uniform)")
plt.legend()
plt.title(f"exact integral of f: {I_EXACT:.5f}")
plt.show()

# %% [markdown]
# ## Streaming RIS
#
# Each of the $n$ candidates $x_i$ gets the resampling weight
# $w_i = m_i\,\hat p(x_i) / p(x_i)$ with $m_i = 1/n$. One candidate $Y$ is kept with
# probability $w_i / w_\mathrm{sum}$ and given $W = w_\mathrm{sum} / \hat p(Y)$; then
# $f(Y)\,W$ is an unbiased estimate of $\int f$.
#
# The candidates stream past one at a time, as they do on the GPU: after adding $w_i$ to the
# running sum, candidate $i$ replaces the current choice when $u_i\,w_\mathrm{sum} < w_i$,
# with $u_i$ uniform. Candidate $i$ then survives every later replacement with exactly the
# probability $w_i / w_\mathrm{sum}$ of the whole stream. Trials run side by side as numpy rows.

# %%
def ris(x, u):
    """Streaming RIS over candidates x (trials, n) drawn uniformly, one uniform number u per
    candidate: the selected sample Y, its W, and the selected index."""
    trials, n = x.shape
    w = p_hat(x) / n                      # m_i p_hat(x_i) / p(x_i), with p = 1 and m_i = 1 / n
    w_sum = np.zeros(trials)
    selected = np.full(trials, -1)
    for i in range(n):
        w_sum = w_sum + w[:, i]
        selected = np.where(u[:, i] * w_sum < w[:, i], i, selected)
    y = x[np.arange(trials), selected]
    return y, w_sum / p_hat(y), selected


# %% [markdown]
# ### The estimate converges to the exact integral
#
# For every candidate count the mean of $f(Y)\,W$ over many independent trials matches the
# exact integral within a few standard errors; more candidates bring $Y$ closer to $\hat p$ and
# lower the variance (down to the floor set by how far $\hat p$ is from $f$).

# %%
TRIALS = 200_000
print(f"exact {I_EXACT:.5f}")
for n in (1, 2, 4, 8, 32):
    y, W, _ = ris(rng.random((TRIALS, n)), rng.random((TRIALS, n)))
    est = f(y) * W
    se = est.std(ddof=1) / np.sqrt(TRIALS)
    z = (est.mean() - I_EXACT) / se
    print(f"n = {n:2d}: mean {est.mean():.5f} +- {se:.5f} (z = {z:+.2f}), variance of one estimate {est.var():.4f}")
    assert abs(z) < 4.5

# %%
y, W, _ = ris(rng.random((TRIALS, 8)), rng.random((TRIALS, 8)))
est = f(y) * W
k = np.arange(1, TRIALS + 1)
running = np.cumsum(est) / k
band = 2.0 * est.std() / np.sqrt(k)
plt.figure(figsize=(6, 3))
plt.semilogx(k, running, label="running mean of f(Y) W, n = 8")
plt.fill_between(k, I_EXACT - band, I_EXACT + band, color="grey", alpha=0.3, label="exact +- 2 standard errors")
plt.axhline(I_EXACT, color="k", lw=0.8)
plt.ylim(I_EXACT - 0.3, I_EXACT + 0.3)
plt.xlabel("trials")
plt.legend()
plt.show()

# %% [markdown]
# ### W is, on average, the reciprocal density of Y
#
# The density $p_Y$ of the selected sample has no closed form (it is a marginal over the
# candidates that lost), but a histogram of many $Y$ estimates it. In every bin the mean of
# $W$ should equal $1 / p_Y$: that is what makes $W$ an unbiased contribution weight. With
# few candidates $p_Y$ is still far from $\hat p$ normalized, and so $W$ is not
# $1 / \hat p$ normalized either.

# %%
n, trials, bins = 4, 1_000_000, 40
y, W, _ = ris(rng.random((trials, n)), rng.random((trials, n)))
counts, edges = np.histogram(y, bins=bins, range=(0.0, 1.0))
p_Y = counts / trials * bins                               # histogram estimate of the density of Y
mean_W = np.bincount(np.minimum((y * bins).astype(int), bins - 1), weights=W, minlength=bins) / counts
centres = 0.5 * (edges[:-1] + edges[1:])
p_hat_norm = p_hat(xs) / (0.3 + 3.0 * (0.5 - np.sin(10.0) / 20.0))  # divided by its integral

plt.figure(figsize=(6, 3))
plt.plot(centres, mean_W, "o", ms=4, label="mean of W in each bin of Y")
plt.plot(centres, 1.0 / p_Y, "-", label="1 / p_Y (histogram)")
plt.plot(xs, 1.0 / p_hat_norm, ":", label=r"1 / $\hat p$ normalized")
plt.xlabel("y")
plt.legend()
plt.show()
deviation = np.abs(mean_W * p_Y - 1.0)
print(f"|mean W x p_Y - 1| per bin: median {np.median(deviation):.4f}, largest {deviation.max():.4f}")
assert np.median(deviation) < 0.02

# %% [markdown]
# ## Reservoirs
#
# A reservoir stores the selected sample with its $W$ and its confidence $M$; the running
# sum $w_\mathrm{sum}$ exists only while a pass streams its inputs. Two reservoirs of the same
# domain merge like candidates, with the resampling weight $m_j\,\hat p(y_j)\,W_j$ and MIS
# weights proportional to the confidences (with one target function the balance heuristic
# reduces to $m_j = M_j / \sum_k M_k$). Two reservoirs of 4 candidates each, merged, select
# exactly as one RIS over all 8 candidates would: the same mean and the same variance.

# %%
def merge(y1, W1, M1, y2, W2, M2, u):
    """Merge two reservoirs of one domain (identity shift, J = 1), streaming the first then the
    second, each with its own uniform number (u: (trials, 2))."""
    w1 = M1 / (M1 + M2) * p_hat(y1) * W1
    w2 = M2 / (M1 + M2) * p_hat(y2) * W2
    w_sum = w1 + w2
    take1 = u[:, 0] * w1 < w1                # the first input, alone in the stream so far
    take2 = u[:, 1] * w_sum < w2
    y = np.where(take2, y2, np.where(take1, y1, np.nan))
    return y, w_sum / p_hat(y), M1 + M2


one = np.ones(TRIALS)
ya, Wa, _ = ris(rng.random((TRIALS, 4)), rng.random((TRIALS, 4)))
yb, Wb, _ = ris(rng.random((TRIALS, 4)), rng.random((TRIALS, 4)))
ym, Wm, Mm = merge(ya, Wa, one, yb, Wb, one, rng.random((TRIALS, 2)))
y8, W8, _ = ris(rng.random((TRIALS, 8)), rng.random((TRIALS, 8)))
for label, e in (("two merged reservoirs of 4", f(ym) * Wm), ("one RIS over 8 candidates", f(y8) * W8)):
    print(f"{label}: mean {e.mean():.5f} +- {e.std() / np.sqrt(TRIALS):.5f}, variance {e.var():.4f}")

# %% [markdown]
# ## Temporal reuse and the confidence cap
#
# ReSTIR keeps each pixel's reservoir from frame to frame. Here one "pixel" (the integral above,
# which does not move) renders frames: each frame draws a fresh reservoir from 2 candidates, with
# confidence $M_c = 1$ as ReSTIR DI gives its initial RIS, and merges it with the previous
# frame's result. The history's confidence is first capped,
# $M_\mathrm{hist} \leftarrow \min(M_\mathrm{hist}, \mathrm{cap} \cdot M_c)$; "no cap" is the
# project's cap of $10^6$ (`NO_CAP_RATIO`). Every frame's estimate stays unbiased whatever the
# cap; what the cap changes is how strongly a frame depends on the frames before it.

# %%
from restir.resampling.ris import NO_CAP_RATIO  # noqa: E402

FRAMES, CANDIDATES, CHAIN_TRIALS = 24, 2, 100_000


def temporal_chain(x, u, cap):
    """x: (trials, frames, candidates) candidates, u: (trials, frames, candidates + 2) uniform
    numbers. Per frame the fresh reservoir (RIS over the candidates, M = 1) merged with the
    previous frame's, the history's confidence capped; returns y, W, M of every frame."""
    trials, frames, _ = x.shape
    ys, Ws, Ms = (np.zeros((trials, frames)) for _ in range(3))
    for t in range(frames):
        y, W, _ = ris(x[:, t], u[:, t, :CANDIDATES])
        M = np.ones(trials)
        if t > 0:
            M_hist = np.minimum(Ms[:, t - 1], (cap if cap > 0 else NO_CAP_RATIO) * M)
            y, W, M = merge(y, W, M, ys[:, t - 1], Ws[:, t - 1], M_hist, u[:, t, CANDIDATES:])
        ys[:, t], Ws[:, t], Ms[:, t] = y, W, M
    return ys, Ws, Ms


x_chain = rng.random((CHAIN_TRIALS, FRAMES, CANDIDATES))
u_chain = rng.random((CHAIN_TRIALS, FRAMES, CANDIDATES + 2))
CAPS = {"cap 1": 1.0, "cap 5": 5.0, "cap 20": 20.0, "no cap": 0.0}
chains = {label: temporal_chain(x_chain, u_chain, cap) for label, cap in CAPS.items()}

# %% [markdown]
# Per frame: the mean over trials against the exact integral (every frame, every cap), the
# relative standard deviation of one frame's estimate, and the correlation between consecutive
# frames. Without temporal reuse every frame would have the noise of frame 0 and no correlation.

# %%
summary = {}
fig, ax = plt.subplots(1, 2, figsize=(11, 3.2))
for label, (ys, Ws, Ms) in chains.items():
    e = f(ys) * Ws
    z = (e.mean(axis=0) - I_EXACT) / (e.std(axis=0, ddof=1) / np.sqrt(CHAIN_TRIALS))
    assert np.all(np.abs(z) < 4.5), (label, z)
    corr = [np.corrcoef(e[:, t - 1], e[:, t])[0, 1] for t in range(1, FRAMES)]
    ax[0].plot(e.std(axis=0) / I_EXACT, label=label)
    ax[1].plot(range(1, FRAMES), corr, label=label)
    summary[label] = noise, memory, averaged = e[:, -1].std() / I_EXACT, corr[-1], e.mean(axis=1).std() / I_EXACT
    print(f"{label:7s}: M at the last frame {Ms[0, -1]:3.0f}; largest |z| over frames {np.abs(z).max():.2f}; "
          f"last frame: relative std {noise:.3f}, correlation with the frame before {memory:.3f}; "
          f"relative error of the {FRAMES}-frame average {averaged:.4f}")
ax[0].set(xlabel="frame", ylabel="relative std of one frame", title="noise of each frame")
ax[1].set(xlabel="frame", ylabel="correlation with the frame before", title="memory")
ax[0].legend()
plt.show()

# %%
noise, memory, averaged = (np.array([summary[k][i] for k in ("cap 1", "cap 5", "no cap")]) for i in range(3))
assert np.all(np.diff(noise) < 0) and np.all(np.diff(memory) > 0) and np.all(np.diff(averaged) > 0)

# %% [markdown]
# The larger the cap, the lower each frame's noise and the stronger its memory: a frame mostly
# keeps the history's sample. A still image averages its frames, and correlated frames average
# out more slowly: here the average of all frames has more error the larger the cap. The cap
# trades noise in each frame against error that lingers (and, once spatial reuse copies samples
# to neighbours, against blotches). ReSTIR DI below shows the same trade on a real scene.
#
# ## The same choices from the renderer's resampling code
#
# The renderer's reuse passes are built from a few Warp functions in `restir/resampling/`:
# `ris_stream` (add one input to the in-flight state), `ris_merge` (add a reservoir with its
# weight $m\,\hat p\,J\,W$), `ris_finalize` ($W$ and $M$ of the result), `cap_history` and
# the two-technique balance weight `talbot_weight2`. The kernel below drives them exactly as
# ReSTIR DI's initial and temporal passes do, over the same candidates and uniform numbers as the
# numpy chain: the selected samples, their $W$ and their $M$ must agree.

# %%
from restir.api import check_device  # noqa: E402
from restir.resampling.mis import talbot_weight2  # noqa: E402
from restir.resampling.ris import cap_history, ris_finalize, ris_init, ris_merge, ris_stream  # noqa: E402

wp = check_device(restir.RenderConfig(device="cpu"))  # Warp, initialized as restir.render initializes it


@wp.func
def p_hat_wp(x: float) -> float:
    s = wp.sin(5.0 * x)
    return 0.3 + 3.0 * s * s


@wp.kernel
def temporal_chain_kernel(x: wp.array3d(dtype=float), u: wp.array3d(dtype=float), cap: float,
                          ys: wp.array2d(dtype=float), Ws: wp.array2d(dtype=float), Ms: wp.array2d(dtype=float)):
    t = wp.tid()
    n = x.shape[2]
    for frame in range(x.shape[1]):
        # the fresh reservoir: streaming RIS over the candidates, confidence 1
        s = ris_init()
        y_c = float(0.0)
        for i in range(n):
            p = p_hat_wp(x[t, frame, i])
            s = ris_stream(s, p / float(n), p, 0.0, i, u[t, frame, i])
            if s.selected == i:
                y_c = x[t, frame, i]
        W_c = ris_finalize(s, 1.0).W
        M_c = float(1.0)  # the initial RIS is one technique of confidence 1, as in ReSTIR DI
        y = y_c
        W = W_c
        M = M_c
        if frame > 0:
            # temporal reuse: the history's confidence capped, balance weights over the two inputs
            y_q = ys[t, frame - 1]
            M_q = cap_history(Ms[t, frame - 1], cap, M_c)
            p_c = p_hat_wp(y_c)
            p_q = p_hat_wp(y_q)
            s = ris_init()
            s = ris_merge(s, talbot_weight2(p_c * M_c, p_c * M_q, 0), p_c, 1.0, W_c, M_c, 0, u[t, frame, n])
            s = ris_merge(s, talbot_weight2(p_q * M_c, p_q * M_q, 1), p_q, 1.0, Ws[t, frame - 1], M_q, 1,
                          u[t, frame, n + 1])
            r = ris_finalize(s, 1.0)
            y = wp.where(s.selected == 1, y_q, y_c)
            W = r.W
            M = r.M
        ys[t, frame] = y
        Ws[t, frame] = W
        Ms[t, frame] = M


def temporal_chain_warp(x, u, cap):
    shape = x.shape[:2]
    out = [wp.zeros(shape, dtype=float, device="cpu") for _ in range(3)]
    wp.launch(temporal_chain_kernel, dim=x.shape[0], device="cpu",
              inputs=[wp.array(x.astype(np.float32), device="cpu"), wp.array(u.astype(np.float32), device="cpu"),
                      float(cap), *out])
    return [o.numpy() for o in out]


# %%
for label, cap in CAPS.items():
    ys, Ws, Ms = chains[label]
    ys_wp, Ws_wp, Ms_wp = temporal_chain_warp(x_chain, u_chain, cap)
    same = np.abs(ys_wp - ys) < 1e-6
    rel_W = np.abs(Ws_wp[same] - Ws[same]) / Ws[same]
    print(f"{label:7s}: same sample in {same.mean():.5%} of trial-frames; where the same, W agrees to "
          f"{np.median(rel_W):.1e} (median) / {rel_W.max():.1e} (largest) relative; M identical: "
          f"{np.array_equal(Ms_wp, Ms)}")
    assert same.mean() > 0.999 and np.percentile(rel_W, 99.9) < 1e-4 and np.array_equal(Ms_wp, Ms)

# %% [markdown]
# The kernel computes in single precision and numpy in double, so they agree to float32 rounding;
# the check allows for a uniform number that falls within rounding of a selection threshold
# $u\,w_\mathrm{sum} = w_i$ and picks the other input (after which that trial's chain would go on
# from another sample).
#
# ## ReSTIR DI on `builtin:many-lights`
#
# The Cornell room lit by 400 small coloured emitters, at 64 x 64 pixels. ReSTIR DI estimates
# direct light (Mitsuba's `max_depth` 2): at each pixel it resamples light candidates (the
# initial RIS), reuses the previous frame's reservoir (temporal reuse, with the cap above) and
# its neighbours' (spatial reuse, whose MIS weights are pairwise), then shades the selected light
# point. The emitters seen directly are the same for every method and are hidden here
# (`hide_emitters`, the parameter of Mitsuba's path integrator), so that the images show only what
# resampling changes. The reference is the path tracer at 512 samples per pixel.

# %%
from restir.compare.metrics import relmse  # noqa: E402
from restir.scene.builtin import many_lights  # noqa: E402

scene_dict = many_lights(width=64, height=64)
scene_dict["integrator"]["hide_emitters"] = True
scene = restir.load_scene(scene_dict)
reference = restir.render(scene, method="pt", max_depth=2, spp=32, frames=16, seed=1)
reference

# %% [markdown]
# The setting keys are those `restir info` lists under `restir-di`: `temporal`,
# `temporal.cap` ($\le 0$: no cap), `spatial.rounds` (0: no spatial reuse, and so no pairwise
# MIS), `candidates` (32 light candidates by default). Each configuration renders 32 frames of
# 1 sample per pixel from one seed, keeping every frame.

# %%
FRAMES_DI = 32
CONFIGS = {
    "path tracer, 1 spp": ("pt", {}),
    "initial RIS only": ("restir-di", {"temporal": False, "spatial.rounds": 0}),
    "+ temporal (cap 5)": ("restir-di", {"spatial.rounds": 0}),
    "+ temporal (no cap)": ("restir-di", {"spatial.rounds": 0, "temporal.cap": 0}),
    "+ spatial (pairwise MIS)": ("restir-di", {"temporal": False}),
    "temporal + spatial (defaults)": ("restir-di", {}),
    "temporal (no cap) + spatial": ("restir-di", {"temporal.cap": 0}),
}
runs = {label: restir.render(scene, method=method, max_depth=2, spp=1, frames=FRAMES_DI, seed=3, settings=settings,
                             keep_frames=True)
        for label, (method, settings) in CONFIGS.items()}
for label, r in runs.items():
    print(f"{label:30s} {r.stats['ms_per_frame']:6.1f} ms per frame")

# %% [markdown]
# The last frame of a few configurations next to the reference (one frame each, not the average):

# %%
def show(images, titles):
    fig, axes = plt.subplots(1, len(images), figsize=(3 * len(images), 3.2))
    for a, img, title in zip(np.atleast_1d(axes), images, titles):
        a.imshow(np.clip(img, 0.0, 1.0) ** (1 / 2.2))  # linear RGB to a display gamma
        a.set_title(title, fontsize=9)
        a.axis("off")
    plt.show()


picked = ["path tracer, 1 spp", "initial RIS only", "temporal + spatial (defaults)"]
show([runs[k].frame_images[-1] for k in picked] + [reference.image], picked + ["reference"])

# %% [markdown]
# Error against the reference (relMSE, `restir.compare.metrics.relmse`), of each frame alone
# and of the average of the frames so far:

# %%
frame_error = {k: np.array([relmse(x, reference.image) for x in r.frame_images]) for k, r in runs.items()}
accumulated = {}
for k, r in runs.items():
    avg = np.cumsum(r.frame_images, axis=0) / np.arange(1, FRAMES_DI + 1)[:, None, None, None]
    accumulated[k] = np.array([relmse(a, reference.image) for a in avg])

fig, ax = plt.subplots(1, 2, figsize=(12, 3.8))
for k in runs:
    ax[0].semilogy(frame_error[k], label=k)
    ax[1].loglog(np.arange(1, FRAMES_DI + 1), accumulated[k], label=k)
ax[0].set(xlabel="frame", ylabel="relMSE of the frame", title="each frame")
ax[1].set(xlabel="frames averaged", ylabel="relMSE of the average", title="accumulated")
ax[1].legend(fontsize=7)
plt.show()
for k in runs:
    print(f"{k:30s} frames 8-31: mean relMSE per frame {frame_error[k][8:].mean():.3f}; "
          f"average of {FRAMES_DI} frames {accumulated[k][-1]:.4f}")

# %% [markdown]
# What to read in the plots (the printed numbers are this run's):
#
# - Resampling 32 light candidates by their contribution puts each frame's one light sample where
#   the light is: the initial RIS alone has far less error per frame than the path tracer at one
#   sample per pixel (at a higher cost per frame).
# - Temporal reuse lowers each frame's error further once the history has built up, but the
#   frames are no longer independent, so their average converges more slowly than the average of
#   independent frames. Without a cap the history dominates more and more (its confidence grows
#   every frame), and the error of the average stays higher still: the numpy chain above in a
#   real scene.
# - Spatial reuse borrows the neighbours' reservoirs. Their samples were drawn for other
#   pixels, and the pairwise MIS weights (see [MIS weights](../../theory/mis/)) are what keep the
#   result unbiased.
#
# One run per configuration measures error, not bias: the statistical tests of the methods
# against the path tracer, with independent runs, are described on the
# [Validation](../../validation/) page. How much reuse pays at equal time, and after a denoiser,
# is measured in the user guide's [When does ReSTIR pay?](../../guide/when_restir_pays/).

# %%
assert frame_error["initial RIS only"].mean() < frame_error["path tracer, 1 spp"].mean()
assert frame_error["+ temporal (cap 5)"][8:].mean() < frame_error["initial RIS only"][8:].mean()
final = {k: v[-1] for k, v in accumulated.items()}
assert final["initial RIS only"] < final["+ temporal (cap 5)"] < final["+ temporal (no cap)"]
