"""One module per material kind, each with its eval, pdf, sample and lobes together (as pbrt keeps
one BxDF's functions together); `device/bsdf.py` dispatches over them.

- material.py: the `Material` record, `BSDFSample`, and the helpers every kind uses.
- diffuse.py: Lambertian reflection.
- conductor.py: smooth and rough conductors (Fresnel of a complex IOR).
- dielectric.py: smooth, thin and rough dielectrics.
- plastic.py: Mitsuba's smooth and rough plastic (a dielectric coat over a diffuse base).
- metallic_roughness.py: glTF 2.0's metallic-roughness material.
- diffuse_transmission.py: pbrt-v4's diffuse reflection and transmission.
- registry.py: the table of kinds that the dispatch in device/bsdf.py is checked against.

Every function works in the local shading frame on the material's front side: the dispatcher
mirrors two-sided materials hit from the back before calling them. A kind's `*_sample` picks the
lobe and the direction; for a delta lobe it also sets the pdf and the weight, and every other
sample is weighted by the dispatcher with the kind's own eval and pdf (so weight = eval / pdf
holds by construction). Parameters arrive resolved
(textures already looked up by `scene_device.textured_material`), so a kind never reads a texture.
"""
