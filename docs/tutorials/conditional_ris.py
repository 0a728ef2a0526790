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
# # Conditional RIS and Suffix ReSTIR
#
# ReSTIR PT resamples whole paths, and its spatial reuse copies a good path into many neighbouring
# pixels: the error of nearby pixels is shared. Suffix ReSTIR splits each path into a *prefix*
# (from the camera to a vertex after the first rough bounce) and a *suffix* (the rest), resamples
# only the suffixes, and integrates every pixel through prefixes of its own. The resampling of a
# suffix for a given prefix is *conditional RIS*.
#
# This tutorial runs conditional RIS on a two-dimensional toy integral with the renderer's
# resampling code, then compares Suffix ReSTIR with ReSTIR PT on `builtin:indirect-room`: their
# error, and how much of it neighbouring pixels share. Background:
# [Conditional RIS and Suffix ReSTIR](../../theory/suffix_restir/). The notebook runs from
# `docs/tutorials/` in a checkout of the repository, with the project's virtual environment as its
# kernel.

# %%
import pathlib
import sys

import matplotlib.pyplot as plt
import numpy as np

# the repository's root (this notebook lives in docs/tutorials/): restir and tests import from there
ROOT = next(p for p in (pathlib.Path.cwd(), *pathlib.Path.cwd().parents) if (p / "restir" / "__init__.py").is_file())
sys.path.insert(0, str(ROOT))

import restir  # noqa: E402
from restir.api import check_device  # noqa: E402

wp = check_device(restir.RenderConfig(device="cpu"))  # Warp, initialized as restir.render initializes it

# %% [markdown]
# ## Conditional RIS on a toy integral
#
# Write an integral over pairs, a prefix $y$ and a suffix $x$ that continues it:
#
# $$
# I = \int_0^1 \int_0^1 g(y)\,h(y, x)\,\mathrm{d}x\,\mathrm{d}y .
# $$
#
# If $W_y$ is an unbiased contribution weight for the prefix, and $W_{x \mid y}$ one for the
# suffix *given* the prefix (for every value of $y$), then their product is one for the pair:
# $g(y)\,W_y\,h(y, x)\,W_{x \mid y}$ estimates $I$ without bias.
#
# The unit test `tests/unit/test_cris_toy.py` builds exactly this with the production resampling
# core (`ris_stream`, `ris_merge`, `ris_finalize` and the balance heuristic `balance_weight`):
#
# - **the prefix** $y$: RIS over $C$ uniform candidates with target $g$, giving $W_y$;
# - **other prefixes' suffix reservoirs**: $K$ prefixes $y_j$ drawn independently of $y$,
#   each with a suffix $x_j$ resampled for it (target $h(y_j, \cdot)$) and its weight $W_j$;
# - **the suffix of $y$**: conditional RIS over a fresh canonical candidate and the $K$
#   reservoirs, each shifted into $y$'s domain by $T_j(x) = (x + y - y_j) \bmod 1$ ($J = 1$),
#   with generalized balance MIS weights over the $K + 1$ techniques; this gives
#   $W_{x \mid y}$.
#
# What makes $W_{x \mid y}$ conditional is that the suffix reservoirs' randomness does not depend
# on how $y$ was chosen. The test also has a *violating* variant that breaks this: it selects the
# prefix by the joint value $g(y_k)\,h(y_k, x_k)$ of each prefix candidate and a suffix candidate
# of its own, then reuses that suffix candidate as the canonical one while still claiming the
# $W_y$ of the marginal target $g$.

# %%
from tests.unit.test_cris_toy import cris_kernel, exact  # noqa: E402

I_EXACT = exact()
TRIALS = 1 << 19


def cris(candidates, K, violate, seed=5):
    """One estimate g(y) W_y h(y, x) W_{x|y} per independent trial, from the test's kernel."""
    out = wp.zeros(TRIALS, dtype=float, device="cpu")
    wp.launch(cris_kernel, dim=TRIALS, inputs=[candidates, K, violate, seed, out], device="cpu")
    return out.numpy().astype(np.float64)


CASES = {"C=1, K=0": (1, 0, 0), "C=1, K=3": (1, 3, 0), "C=4, K=3": (4, 3, 0), "C=4, K=8": (4, 8, 0),
         "violating, C=4, K=3": (4, 3, 1)}
toy = {label: cris(*args) for label, args in CASES.items()}
for label, v in toy.items():
    se = v.std(ddof=1) / np.sqrt(TRIALS)
    print(f"{label:20s} mean {v.mean():.5f} (exact {I_EXACT:.5f}), z = {(v.mean() - I_EXACT) / se:+7.2f}, "
          f"variance of one estimate {v.var():.4f}")

# %%
labels = list(toy)
dev = [100 * (toy[k].mean() / I_EXACT - 1) for k in labels]
err = [100 * 3 * toy[k].std() / np.sqrt(TRIALS) / I_EXACT for k in labels]
plt.figure(figsize=(7, 3))
plt.errorbar(range(len(labels)), dev, yerr=err, fmt="o", capsize=4)
plt.axhline(0, color="k", lw=0.8)
plt.xticks(range(len(labels)), labels, rotation=15)
plt.ylabel("deviation from I (%), +- 3 s.e.")
plt.show()
for label, (_, _, violate) in CASES.items():
    z = (toy[label].mean() - I_EXACT) / (toy[label].std(ddof=1) / np.sqrt(TRIALS))
    assert (abs(z) > 10) if violate else (abs(z) < 4.5), (label, z)

# %% [markdown]
# Every conditional configuration is unbiased, and borrowing other prefixes' suffixes ($K > 0$)
# lowers the variance; the violating variant is far off, though it uses the same resampling
# functions: what matters is where the inputs' randomness comes from.
#
# ## From the toy to Suffix ReSTIR
#
# In the renderer a prefix ends one vertex after the first rough bounce (the *prefix end*
# $x_P$), and a suffix domain is that end point with the direction the prefix arrived from. Each
# frame, per pixel:
#
# 1. **prefix resampling**: a fresh prefix is traced and resampled with the previous frame's
#    (temporal reuse); this only decides *where* the pixel's suffix domain lies;
# 2. **suffix reservoirs**: a suffix is traced from that prefix end and reused temporally and
#    spatially with ReSTIR PT's shifts, started at $x_P$ instead of the primary hit;
# 3. **the final gather**: $N$ *fresh* prefixes (`gather.prefixes`, 4) are traced with new
#    random numbers. Each looks up the suffix reservoirs of pixels whose prefix ends lie near its
#    own end point (the prefix search), shifts $M$ of them (`gather.suffixes`, 1) into its suffix
#    domain, and resamples them, with a canonical suffix traced fresh for prefix 0 and weighted by
#    $N$. The pixel's value is
#
# $$
# L = L_\mathrm{direct} + \frac{1}{N} \sum_{i=0}^{N-1} \big(\text{internal}_i + \beta_P^{(i)}\,S_i\big),
# $$
#
# with $\beta_P^{(i)}$ the throughput of prefix $i$, $S_i$ its resampled suffix estimate, and
# "internal" the light a prefix finds before its end. The gather is the toy's conditional RIS:
# the fresh prefixes are drawn after, and independently of, every suffix reservoir they gather,
# so each reservoir's $W_j$ stays a conditional weight for whichever prefix it lands on.
#
# ## Suffix ReSTIR against ReSTIR PT
#
# `builtin:indirect-room` at 64 x 64, lit almost only indirectly, `max_depth` 5 for every method,
# each method's default settings, 16 frames of 1 sample per pixel. The reference is the path
# tracer at 1024 samples per pixel.

# %%
from restir.compare.metrics import relmse  # noqa: E402
from restir.compare.structure import (correlation_factor, radial_correlation, relative_error,  # noqa: E402
                                      temporal_correlation)

room = restir.load_scene("builtin:indirect-room", width=64, height=64)
DEPTH, FRAMES = 5, 16
reference = restir.render(room, method="pt", max_depth=DEPTH, spp=64, frames=16, seed=1)
METHODS = ["pt", "restir-pt", "suffix-restir"]
runs = {m: restir.render(room, method=m, max_depth=DEPTH, spp=1, frames=FRAMES, seed=3, keep_frames=True)
        for m in METHODS}
for m, r in runs.items():
    print(f"{m:14s} {r.stats['ms_per_frame']:6.1f} ms per frame")

# %%
fig, ax = plt.subplots(1, 4, figsize=(13, 3.4))
for a, (title, img) in zip(ax, [*((f"{m}, frame {FRAMES - 1}", r.frame_images[-1]) for m, r in runs.items()),
                                ("reference", reference.image)]):
    a.imshow(np.clip(img, 0, 1) ** (1 / 2.2))
    a.set_title(title, fontsize=9)
    a.axis("off")
plt.show()

# %% [markdown]
# Error against the reference: relMSE of each frame, and of the average of the frames so far.

# %%
fig, ax = plt.subplots(1, 2, figsize=(11, 3.4))
for m, r in runs.items():
    per_frame = [relmse(x, reference.image) for x in r.frame_images]
    avg = np.cumsum(r.frame_images, axis=0) / np.arange(1, FRAMES + 1)[:, None, None, None]
    ax[0].semilogy(per_frame, label=m)
    ax[1].loglog(np.arange(1, FRAMES + 1), [relmse(a, reference.image) for a in avg], label=m)
    print(f"{m:14s} relMSE per frame (mean of frames 4-15) {np.mean(per_frame[4:]):.3f}, "
          f"of the {FRAMES}-frame average {relmse(r.image, reference.image):.4f}")
ax[0].set(xlabel="frame", ylabel="relMSE", title="each frame")
ax[1].set(xlabel="frames averaged", ylabel="relMSE", title="accumulated")
ax[0].legend()
plt.show()

# %% [markdown]
# ## How much of the error neighbours share
#
# `restir/compare/structure.py` has the measures `restir compare` reports (the user guide's
# [Comparing methods](../../guide/compare/) derives them), all computed on the relative error
# $e = (x - \mathrm{ref}) / \sqrt{\mathrm{ref}^2 + 0.01}$:
#
# - **radial correlation**: from $K$ independent runs at one frame index, each pixel standardized
#   over the runs, the correlation of pixel $p$ with the pixels on the square ring at distance
#   $r$ around it; 0 for independent pixels, reported with the standard error it would have
#   under independence;
# - **correlation factor** $F_B$: how much of a frame's squared error survives averaging over
#   $B \times B$ blocks, relative to independent pixels (1: independent, $B^2$: constant over
#   each block);
# - **temporal correlation**: the correlation of consecutive frames' errors.
#
# A denoiser averages neighbouring pixels, so it removes independent error well and shared error
# badly. The radial correlation needs independent runs: 8 per method, each 12 frames long, the
# ring correlation measured on their last frame. Spatial reuse picks its neighbours in a disk, by
# default 20 px for ReSTIR PT and 30 px for Suffix ReSTIR's suffix reuse: the larger the disk, the
# more pixels a copy of a sample can land on, and the weaker the correlation of any one pair of
# pixels. The measurement is repeated with a 4-pixel disk (`spatial.radius`,
# `suffix.spatial.radius`), where the copies of a sample land close together.

# %%
K_RUNS, CORR_FRAMES = 8, 12
RADIUS = {"pt": {}, "restir-pt": {"spatial.radius": 4}, "suffix-restir": {"suffix.spatial.radius": 4}}


def structure(method, settings):
    last = np.stack([restir.render(room, method=method, max_depth=DEPTH, spp=1, frames=CORR_FRAMES, seed=100 + k,
                                   settings=settings, keep_frames=True).frame_images[-1] for k in range(K_RUNS)])
    values, errors = radial_correlation(last)
    return np.array(values), np.array(errors)


radial = {}
for m in METHODS:
    radial[m] = structure(m, {})
    if RADIUS[m]:
        radial[f"{m}, 4-px disk"] = structure(m, RADIUS[m])

# %%
radii = np.arange(1, 17)
plt.figure(figsize=(7, 3.6))
for label, (v, e) in radial.items():
    plt.errorbar(radii, v, yerr=e, fmt="o-", ms=3, capsize=2, label=label)
plt.axhline(0, color="k", lw=0.8)
plt.xlabel("ring radius r (pixels)")
plt.ylabel("radial correlation")
plt.legend(fontsize=8)
plt.show()
for label, (v, e) in radial.items():
    print(f"{label:26s} r = 1: {v[0]:+.3f} +- {e[0]:.3f}, r = 4: {v[3]:+.3f} +- {e[3]:.3f}")

# %% [markdown]
# The correlation factor and the temporal correlation, from the 16-frame runs above (means over
# frames 4-15):

# %%
temporal = {}
for m, r in runs.items():
    e = [relative_error(x, reference.image) for x in r.frame_images]
    factors = [np.mean([correlation_factor(x, B) for x in e[4:]]) for B in (2, 4, 8, 16)]
    temporal[m] = np.mean([temporal_correlation(e[i - 1], e[i]) for i in range(5, FRAMES)])
    print(f"{m:14s} F_2, F_4, F_8, F_16 = {', '.join(f'{x:.2f}' for x in factors)}; "
          f"temporal correlation {temporal[m]:.3f}")

# %% [markdown]
# What the measurements show (the printed numbers are this run's):
#
# - ReSTIR PT's error is shared: its frames carry their samples forward (a strong temporal
#   correlation); with the default disk the correlation of one pair of nearby pixels is small but
#   several standard errors above zero, and with the small disk it is strong at short range and
#   falls off over a few pixels.
# - Suffix ReSTIR's error is close to the path tracer's: near zero at every radius and in time.
#   Each pixel is integrated through fresh prefixes of its own; a gathered suffix enters only
#   through a prefix, reconnected from that prefix's own end point and scaled by its own
#   throughput, and which suffixes a prefix gathers depends on where in the scene its end lands,
#   not on where its pixel is on the screen.
#
# The equal-time comparisons, raw and after a denoiser, are in the user guide's
# [When does ReSTIR pay?](../../guide/when_restir_pays/).

# %%
assert radial["restir-pt"][0][0] > 3 * radial["restir-pt"][1][0]
assert radial["restir-pt, 4-px disk"][0][0] > 5 * radial["restir-pt"][0][0]
assert abs(radial["suffix-restir, 4-px disk"][0][0]) < radial["restir-pt, 4-px disk"][0][0] / 4
assert temporal["restir-pt"] > 0.2 and abs(temporal["suffix-restir"]) < 0.05
