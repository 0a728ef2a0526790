"""ReSTIR PT (Lin et al. 2022): path reuse with reconnection, random-replay and hybrid shifts.

- params.py: per-frame values of the stages; the shift kinds.
- path_sample.py: the stored path reservoir (fields, flags) and its one `store` function.
- rc_criteria.py: which vertex of a path is its reconnection vertex (ALGORITHMS.md 3.1).
- base_path.py: the base path tracer with streaming RIS over path lengths (2.2).
- shift.py: the one shift (source path, destination primary hit) -> (F, J, valid) (3.2-3.4).
- s1_initial.py, s2_temporal.py, s3_spatial.py, s4_shade.py: the stages, one kernel each.
- pipeline.py: the integrator, a table of contents of stage calls.
"""
