"""Suffix ReSTIR (Kettunen et al. 2023, conditional RIS): prefix reuse, suffix reuse, a prefix
search structure and a final gather (docs/guide/suffix_restir.md).

- params.py: per-frame values of the stages.
- prefix.py: the adaptive prefix end, a traced prefix, the prefix reservoir and its shift.
- domains.py: suffix domains (a pixel's resampled prefix end) and their path-reuse parameters.
- s1_prefix.py .. s5_gather.py: the stages in execution order (s2_search.py also holds the search
  structures, sorted grid, hash grid and BVH, and the neighbour query the gather calls).
- pipeline.py: the integrator, a table of contents of stage calls.
Suffixes are path samples whose start vertex is the prefix end: the path-reuse package's
reservoir, base path, shift and reuse pair (`integrators/path_reuse/`) serve them unchanged.
"""
