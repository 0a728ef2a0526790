"""Named tags shared by host and device code (never bare integers in kernels)."""
import warp as wp

# Material kinds (bsdfs/registry.py lists them with their modules; `twosided` is a flag, not a kind).
MAT_DIFFUSE = wp.constant(0)
MAT_CONDUCTOR = wp.constant(1)
MAT_ROUGHCONDUCTOR = wp.constant(2)
MAT_DIELECTRIC = wp.constant(3)
MAT_THINDIELECTRIC = wp.constant(4)
MAT_ROUGHDIELECTRIC = wp.constant(5)
MAT_PLASTIC = wp.constant(6)
MAT_ROUGHPLASTIC = wp.constant(7)
MAT_METALLIC_ROUGHNESS = wp.constant(8)  # glTF 2.0's (not a Mitsuba plugin: restir's `metallic_roughness`)
MAT_DIFFUSE_TRANSMISSION = wp.constant(9)  # pbrt-v4's `diffusetransmission` (restir's `diffuse_transmission`)

# How a textured roughness becomes a microfacet alpha (Material.roughness_remap).
ROUGHNESS_IS_ALPHA = wp.constant(0)   # Mitsuba 3's textured alpha
ROUGHNESS_SQRT = wp.constant(1)       # pbrt-v4's remapped roughness: alpha = sqrt(r)
ROUGHNESS_SQUARED = wp.constant(2)    # glTF's perceptual roughness: alpha = r^2

# Microfacet distributions.
MICROFACET_BECKMANN = wp.constant(0)
MICROFACET_GGX = wp.constant(1)

# Reconstruction filters (sampled by filter importance sampling).
FILTER_BOX = wp.constant(0)
FILTER_TENT = wp.constant(1)
FILTER_GAUSSIAN = wp.constant(2)

# Environment emitter kinds.
ENV_NONE = wp.constant(0)
ENV_CONSTANT = wp.constant(1)
ENV_MAP = wp.constant(2)

# Path-tracer estimator strategies (the three must agree in expectation).
STRATEGY_MIS = wp.constant(0)
STRATEGY_NEE = wp.constant(1)
STRATEGY_BSDF = wp.constant(2)

PI = wp.constant(3.14159265358979323846)
INV_PI = wp.constant(0.31830988618379067154)
INV_TWO_PI = wp.constant(0.15915494309189533577)
INV_FOUR_PI = wp.constant(0.07957747154594766788)

# Light-sample identities (a light sample's `tri` field, and reservoirs that store one).
LIGHT_ENV = wp.constant(-1)    # a direction toward the environment
LIGHT_NONE = wp.constant(-2)   # no sample (a reservoir that selected nothing)
NO_TRIANGLE = wp.constant(-1)  # a ray that hit nothing
LIGHT_DELTA_BASE = wp.constant(-3)  # delta light i (device/delta_lights.py) is LIGHT_DELTA_BASE - i

# Delta lights (device/delta_lights.py): a point, a spot (a point with a falloff about its axis),
# and a directional light (parallel light from one direction, as the sun).
DELTA_POINT = wp.constant(0)
DELTA_SPOT = wp.constant(1)
DELTA_DIRECTIONAL = wp.constant(2)

# A spot light's falloff between its inner and outer cone, each as its file format defines it.
FALLOFF_LINEAR_ANGLE = wp.constant(0)  # Mitsuba 3: linear in the angle from the axis
FALLOFF_SMOOTHSTEP = wp.constant(1)    # pbrt-v4: smoothstep in the cosine
FALLOFF_SQUARED_RAMP = wp.constant(2)  # glTF (KHR_lights_punctual): a linear ramp in the cosine, squared

# BSDF lobes (bit flags). A BSDF sample reports the lobe it chose; restricted eval and pdf take a
# mask of lobes. "Glossy" is a rough microfacet lobe, "delta" an ideal specular one.
LOBE_DIFFUSE_REFLECTION = wp.constant(1)
LOBE_DIFFUSE_TRANSMISSION = wp.constant(2)
LOBE_GLOSSY_REFLECTION = wp.constant(4)
LOBE_GLOSSY_TRANSMISSION = wp.constant(8)
LOBE_DELTA_REFLECTION = wp.constant(16)
LOBE_DELTA_TRANSMISSION = wp.constant(32)
LOBE_NULL = wp.constant(64)  # a mask's pass-through: straight on, no scattering (Mitsuba's Null)
LOBES_DIFFUSE = wp.constant(3)
LOBES_GLOSSY = wp.constant(12)
LOBES_DELTA = wp.constant(112)  # the null lobe is a delta lobe, as in Mitsuba
LOBES_ALL = wp.constant(127)
