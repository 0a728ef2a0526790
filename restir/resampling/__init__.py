"""The resampling core shared by ReSTIR DI, ReSTIR PT and Suffix ReSTIR.

- ris.py: the in-flight RIS state (w_sum) and its finalisation to the unbiased contribution
  weight W; streaming selection; the confidence cap (in one place).
- mis.py: resampling MIS weights (pairwise, generalized balance / Talbot, constant-binary) and
  the biased constant 1/M form (only behind an explicit switch).

Everything works on scalars (targets p_hat, Jacobians J, confidences M): the sample payload
(a light sample, a path) is the caller's, copied when `ris_stream` reports it selected.
See docs/theory/notation.md for the symbols.
"""
