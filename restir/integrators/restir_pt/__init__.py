"""ReSTIR PT (Lin et al. 2022): path reuse with reconnection, random-replay and hybrid shifts.

The path samples, base paths, shifts and reuse pairs are the shared path-reuse package
(`integrators/path_reuse/`); this package holds ReSTIR PT's own stages:

- s1_initial.py, s2_temporal.py, s3_mcmc.py, s4_spatial.py, s5_shade.py: the stages, one kernel each.
- kernel_module.py: the Warp module the shipped stage kernels are compiled in.
- pipeline.py: the integrator, a table of contents of stage calls.
"""
