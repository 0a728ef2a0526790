"""The primary-hit layer every method shares (see docs/developer/new_method.md).

- gbuffer.py: the G-buffer (one struct of arrays), its allocation, and ping-pong pairs.
- primary_hits.py: the stage that fills it (camera ray, primary hit, directly seen emission).
- shading.py: loading a pixel's shading frame back from a G-buffer; the surface-similarity test.
- reuse_domains.py: temporal reprojection into the previous camera; spatial neighbour selection;
  the default spatial radius for an image size.
- events.py: the per-pixel event counts every stage writes.
"""
