"""Suffix ReSTIR (Kettunen et al. 2023, conditional RIS): prefix reuse, suffix reuse, a prefix
search structure and a final gather (docs/suffix_restir.md).

- params.py: per-frame values of the stages.
- prefix.py: the adaptive prefix end, a traced prefix, the prefix reservoir and its shift.
- domains.py: suffix domains (a pixel's resampled prefix end) and their path-reuse parameters.
- search.py: the per-pixel boxes, the structures over them (sorted grid, hash grid, BVH) and the neighbour query.
- s1_prefix.py, s3_suffix.py, s5_suffix_spatial.py, s6_gather.py: the stages.
- pipeline.py: the integrator, a table of contents of stage calls.
Suffixes are path samples whose start vertex is the prefix end: the path-reuse package's
reservoir, base path, shift and reuse pair (`integrators/path_reuse/`) serve them unchanged.
"""
