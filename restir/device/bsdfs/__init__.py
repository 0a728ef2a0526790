"""One module per material kind, each with its eval, pdf, sample and lobes together (as pbrt keeps
one BxDF's functions together); `device/bsdf.py` dispatches over them.

- material.py: the `Material` record, `BSDFSample`, and the helpers every kind uses.
- diffuse.py: Lambertian reflection.
- conductor.py: smooth and rough conductors (Fresnel of a complex IOR).
- dielectric.py: smooth, thin and rough dielectrics.
- plastic.py: Mitsuba's smooth and rough plastic (a dielectric coat over a diffuse base).

Every function works in the local shading frame on the material's front side: the dispatcher
mirrors two-sided materials hit from the back before calling them. Parameters arrive resolved
(textures already looked up by `scene_device.material_at`), so a kind never reads a texture.
"""
