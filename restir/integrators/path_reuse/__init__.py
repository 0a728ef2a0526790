"""Path reuse: what ReSTIR PT and Suffix ReSTIR (and any further method that resamples paths) are
built on. Neither method imports the other; both import this package.

- params.py: the per-frame values of a path-reuse domain (`PathReuseParams`); the shift kinds.
- path_sample.py: the stored path reservoir (fields, flags) and its one `store` function.
- rc_criteria.py: which vertex of a path is its reconnection vertex (docs/theory/restir_pt.md#the-reconnection-vertex).
- base_path.py: the base path tracer with streaming RIS over path lengths
  (docs/theory/restir_pt.md#initial-resampling-over-path-lengths).
- domain.py: a shift's destination: a shading point and the domain's parameters (a primary hit
  in ReSTIR PT, a prefix end in Suffix ReSTIR).
- shift.py: the one shift (source path, destination domain) -> (F, J, valid)
  (docs/theory/restir_pt.md#the-hybrid-shift).
- reuse_pair.py: a shift in both directions and the MIS weights of temporal and spatial reuse.
- integrator.py: `PathReuseIntegrator`, the base of the methods: shared settings checks, the
  primary-hit layer, the reservoirs' ping-pong, shift statistics, the per-sample loop.
- direct_light.py: ReSTIR DI as the direct-light component these methods attach (`direct=restir-di`).
"""
