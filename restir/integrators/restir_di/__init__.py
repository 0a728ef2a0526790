"""ReSTIR DI (Bitterli et al. 2020) on the shared resampling core (docs/guide/restir_di.md,
docs/theory/restir_di.md). After the primary hits (common/primary_hits.py), one file per stage:

    s1_initial.py     initial resampling: RIS over light and BSDF candidates
    s2_visibility.py  a shadow ray for the chosen sample (visibility-aware targets)
    s3_temporal.py    temporal reuse with last frame's reservoir at the reprojected pixel
    s4_spatial.py     spatial reuse: pairwise MIS over the pixel and its neighbours
    s5_shade.py       the pixel's estimate of direct illumination

reservoir.py holds the stored reservoir and its integrand, params.py the per-frame values the
stages read, pipeline.py the integrator (its typed settings and the frame's passes), and
kernel_module.py the Warp module of the split stages (`stages.split`).
"""
