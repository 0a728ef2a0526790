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
# # Shift mappings
#
# Spatial and temporal reuse hand a pixel a path that was sampled for another pixel. Before it can
# be resampled there, the path is *shifted*: mapped to a path that starts at this pixel's primary
# hit. The shift changes the measure the path lives in, and the resampling weight must carry the
# shift's Jacobian $J$: $w = m\,\hat p_\mathrm{dst}(T(x))\,J\,W$. This tutorial takes the
# reconnection shift of ReSTIR PT, checks its $J$ against finite differences, and shows the bias
# an image gets when $J$ is wrong.
#
# Background: [Generalized RIS, shifts and Jacobians](../../theory/gris/) and the reconnection
# sections of [ReSTIR PT](../../theory/restir_pt/). The notebook runs from `docs/tutorials/` in a
# checkout of the repository, with the project's virtual environment as its kernel.

# %%
import pathlib
import sys

import matplotlib.pyplot as plt
import numpy as np

# the repository's root (this notebook lives in docs/tutorials/): restir and tests import from there
ROOT = next(p for p in (pathlib.Path.cwd(), *pathlib.Path.cwd().parents) if (p / "restir" / "__init__.py").is_file())
sys.path.insert(0, str(ROOT))

import restir  # noqa: E402
from restir.api import check_device, make_integrator  # noqa: E402

# %% [markdown]
# ## The reconnection shift
#
# A path sample starts at its pixel's primary hit $x_0$. With `shift=reconnection` the shift to
# another pixel keeps the source path's vertex $z = x_1$ and everything after it, and connects
# the destination's primary hit $y_0$ straight to $z$. The shared tail is reached from a
# different vertex, so the random numbers that would have produced it at the destination differ
# from the source's. In primary sample space (a path as the function of its random numbers
# $u$) the Jacobian is the determinant of $\partial u' / \partial u$, which works out to
#
# $$
# J = \frac{G(y_0, z)\;p_\mathrm{lobe}(y_0 \to z)\;p_\mathrm{lobe}(z \to \omega_z \mid y_0)}
#          {G(x_0, z)\;p_\mathrm{lobe}(x_0 \to z)\;p_\mathrm{lobe}(z \to \omega_z \mid x_0)} ,
# $$
#
# with $G = |\cos\theta_z| / d^2$, the lobe densities of the recorded lobes, and the factor at
# $z$ present only where the path scatters on from $z$ in the direction $\omega_z$.
#
# We take the base paths of one frame of ReSTIR PT on `builtin:indirect-room` (glossy floor,
# block and back wall, so that many $z$ are glossy), with reuse off so that every pixel's
# reservoir holds its own freshly traced path.

# %%
scene = restir.load_scene("builtin:indirect-room", width=64, height=64)
config = restir.RenderConfig(method="restir-pt", spp=1, max_depth=6, seed=5,
                             settings={"shift": "reconnection", "temporal": False, "spatial.rounds": 0})
check_device(config)  # Warp initialized for the device, as restir.render does it
integ = make_integrator(scene, config)
frame, _ = integ.render_frame(0)
plt.imshow(np.clip(frame, 0, 1) ** (1 / 2.2))
plt.title("one frame, 1 path per pixel")
plt.axis("off")
plt.show()

# %% [markdown]
# ## The Jacobian against finite differences
#
# The test suite's shift harness (`tests/unit/shift_harness.py`) shifts every pixel's path to a
# partner pixel with the production shift (`restir/integrators/path_reuse/shift.py`) and, next to
# the $J$ it returns, measures $|\det \partial u' / \partial u|$ directly: it perturbs the
# source's random numbers of the bounce that reaches $z$ (and of the bounce at $z$), traces
# the perturbed paths with the production samplers, maps each result back to the destination's
# numbers through the inverse samplers, and takes central differences (Richardson-extrapolated).
# Nothing of the formula above enters the finite differences. Rows where a reconnection segment
# grazes a surface, or where $J$ is so extreme that float32 differences lose their digits, are
# set aside by `well_conditioned` (and counted).

# %%
from tests.unit.shift_harness import describe, relative_errors, run_fd, well_conditioned  # noqa: E402

# columns of a row: 1 = J from the shift, 2 = J from finite differences, 5 = whether z scatters on,
# 6 = the material kind at z
rows = well_conditioned(run_fd(integ, integ.params(0, 0), integ.gbuffers.previous, integ.reservoirs.previous))
rel = relative_errors(rows)
print(describe("indirect-room", "reconnection", rows, rel))
assert len(rows) > 200 and np.median(rel) < 1e-3 and np.percentile(rel, 99) < 1e-2

# %% [markdown]
# ## Builds with a wrong Jacobian
#
# The setting `debug.mutation` selects fault-injected builds that the mutation tests must catch
# (`restir info` lists them per method; the validation harness refuses them unless asked). Two of
# ReSTIR PT's break the Jacobian: `invert_jacobian` uses $1/J$ in place of $J$, and
# `drop_rc_pdf` leaves out the lobe-density ratio at $z$. The same finite differences, run on
# their shifts:

# %%
from restir.device.types import MAT_DIFFUSE  # noqa: E402

MUTANTS = ["invert_jacobian", "drop_rc_pdf"]
checked = {"shipped": (rows, rel)}
for m in MUTANTS:
    r = well_conditioned(run_fd(integ, integ.params(0, 0), integ.gbuffers.previous, integ.reservoirs.previous, m))
    checked[m] = (r, relative_errors(r))
    print(describe("indirect-room", f"reconnection, {m}", r, checked[m][1]))

fig, ax = plt.subplots(1, 3, figsize=(14, 4.4))
for a, (label, (r, e)) in zip(ax, checked.items()):
    glossy = (r[:, 5] > 0) & (r[:, 6] != MAT_DIFFUSE)
    a.loglog(r[~glossy, 2], r[~glossy, 1], ".", ms=3, label="other paths")
    a.loglog(r[glossy, 2], r[glossy, 1], ".", ms=3, label="z scatters on through a glossy lobe")
    lim = [r[:, 1:3].min(), r[:, 1:3].max()]
    a.plot(lim, lim, "k", lw=0.6)
    a.set(title=f"{label}\n99th percentile of the relative error: {np.percentile(e, 99):.1e}",
          xlabel="J, finite differences", ylabel="J returned by the shift")
ax[0].legend(fontsize=8)
plt.show()
for m in MUTANTS:
    assert np.percentile(checked[m][1], 99) > 0.1
r, e = checked["drop_rc_pdf"]
glossy = (r[:, 5] > 0) & (r[:, 6] != MAT_DIFFUSE)
print(f"drop_rc_pdf: relative error above 1% on {np.mean(e[glossy] > 0.01):.0%} of the paths whose z scatters on "
      f"through a glossy lobe, on {np.mean(e[~glossy] > 0.01):.1%} of the others")
assert np.mean(e[glossy] > 0.01) > 0.5 and np.mean(e[~glossy] > 0.01) < 0.01

# %% [markdown]
# The shipped shift lies on the diagonal. The inverted build mirrors it. The build without the
# ratio at $z$ is off where $z$ scatters on through a glossy lobe, whose density for the kept
# direction $\omega_z$ depends on the direction the path arrives from; for a diffuse $z$ that
# ratio is 1, and where $z$ does not scatter there is no such factor.
#
# ## The bias a wrong Jacobian leaves in the image
#
# Leaving out or inverting $J$ does not just add noise: the pass then over-counts paths the
# shift compresses and under-counts those it stretches, and energy moves between regions of the
# image ([the theory](../../theory/gris/)). The validation harness (`restir.validation`) renders
# independent runs of a method (each with its own seed and empty history; each run's statistic is
# its average over its frames) and of the path tracer, and tests them against each other per
# image, per 8 x 8 tile and per pixel, with Welch z-tests at a family-wise false-failure rate of
# $10^{-3}$. Its z-map shows each pixel's z: red where the method is brighter than the path
# tracer, blue where darker, full intensity at $|z| \ge 5$; pixels whose run-to-run statistics
# are too skewed for a z-test are left black.
#
# Here on `builtin:cornell-box` at 32 x 32 (diffuse: its z-tests are better behaved than the glossy
# room's), ReSTIR PT with the reconnection shift and its default temporal and spatial reuse, 16
# runs of 64 frames each side, the path tracer at 4 samples per pixel per frame. `IndependentRuns`
# takes `allow_mutation=True` for the fault-injected build.

# %%
from restir.validation import IndependentRuns, Validation  # noqa: E402
from restir.validation.check import compare  # noqa: E402

box = restir.load_scene("builtin:cornell-box", width=32, height=32)
RUNS, FRAMES, DEPTH = 16, 64, 4
reference = IndependentRuns(box, restir.RenderConfig(method="pt", spp=4, frames=FRAMES, max_depth=DEPTH), RUNS,
                            seed0=900_000)


def check(mutation):
    settings = {"shift": "reconnection", "debug.mutation": mutation}
    runs = IndependentRuns(box, restir.RenderConfig(method="restir-pt", spp=1, frames=FRAMES, max_depth=DEPTH,
                                                    settings=settings),
                           RUNS, seed0=1000, allow_mutation=mutation != "none")
    return Validation(compare(runs, reference.image, reference.batch_variance_of_mean, other=reference), runs,
                      reference)


validations = {"shipped": check("none"), "invert_jacobian": check("invert_jacobian")}
for label, v in validations.items():
    ratio = v.tested.image.mean() / reference.image.mean()
    print(f"{label}: verdict {v.verdict}, image mean / path tracer {ratio:.4f}\n{v.report}")
assert validations["shipped"].verdict == "pass" and validations["invert_jacobian"].verdict == "fail"

# %%
fig, ax = plt.subplots(2, 3, figsize=(10, 7))
images = [reference.image] + [v.tested.image for v in validations.values()]
for a, img, title in zip(ax[0], images, ["path tracer", *validations]):
    a.imshow(np.clip(img, 0, 1) ** (1 / 2.2))
    a.set_title(f"{title} (mean of {RUNS} runs)", fontsize=9)
for a, (label, v) in zip(ax[1, 1:], validations.items()):
    a.imshow(v.zmap())
    a.set_title(f"{label}: z-map ({v.verdict})", fontsize=9)
tile_z = np.mean([r.tile_z for r in validations["invert_jacobian"].report.reports], axis=0).reshape(4, 4)
im = ax[1, 0].imshow(tile_z, cmap="coolwarm", vmin=-12, vmax=12)
ax[1, 0].set_title("invert_jacobian: z of each 8 x 8 tile", fontsize=9)
fig.colorbar(im, ax=ax[1, 0], shrink=0.7)
for a in ax.ravel():
    a.axis("off")
plt.show()

# %% [markdown]
# The shipped build's z-map is noise: no pixel, tile or image mean is further from the path
# tracer than chance allows. With $1/J$, regions of the box come out too bright and others too
# dark; the image level fails by a wide margin, and so do whole tiles.
#
# `drop_rc_pdf` would change nothing on this box beyond float rounding, since its surfaces are
# all diffuse; on the glossy room its effect on the image is small next to the noise of runs this
# size, which is why the finite-difference check above, path by path, is the test that catches
# it. The mutation tests
# and their results are listed on the [Validation](../../validation/) page.
