"""Built-in scenes, written as Mitsuba-style dicts.

- `cornell-box`: the Cornell box from the Cornell University Program of Computer Graphics'
  published measurements (geometry in mm, converted to metres; camera at (278, 273, -800) mm,
  35 mm focal length on a 25 mm film). Spectral reflectances and the light's emission are
  replaced by the RGB values in common use (Bitterli's resources, Mitsuba's `cornell_box()`).
  The light sits 0.1 mm below the ceiling so that the two do not share a plane.
- `cornell-box-glossy`: the same box with a GGX rough-conductor tall block and Beckmann walls.
- `furnace`: a closed sphere, diffuse albedo 0.5, emitting 0.5 everywhere inside; every
  pixel's value is 1 - 0.5^max_depth (1 for unbounded depth).
- `indirect-room`: the Cornell room lit almost only indirectly (its light faces the ceiling
  above a baffle), with glossy surfaces: ReSTIR PT's test and benchmark scene.
- `sphere-cap`: a closed diffuse sphere whose emissive cap covers a fraction `phi` of its area;
  every non-emitting point has the same radiance (see `sphere_cap_radiance`; A1 of
  docs/validation.md#level-2-analytic-scenes-and-external-references).

The two closed spheres default to max_depth ANALYTIC_MAX_DEPTH = 64, not unbounded: no path
ever escapes them and Russian roulette is off by default, so unbounded depth means 1023 bounces
for every path (tens of seconds at 128x128 x 8 spp on the CPU). At albedo 0.5 the truncation
drops a fraction 0.5^64 of the furnace's value and 0.5^63 of the cap sphere's, far below float32
precision; the analytic values for any depth are the formulas above. Pass max_depth=-1 (or
--max-depth -1) for unbounded depth.
"""
import math

import numpy as np

from .errors import SceneError

WHITE = [0.725, 0.71, 0.68]
RED = [0.63, 0.065, 0.05]
GREEN = [0.14, 0.45, 0.091]
LIGHT = [17.0, 12.0, 4.0]

_QUADS = {
    "floor": ([552.8, 0, 0], [0, 0, 0], [0, 0, 559.2], [549.6, 0, 559.2]),
    "ceiling": ([556, 548.8, 0], [556, 548.8, 559.2], [0, 548.8, 559.2], [0, 548.8, 0]),
    "back": ([549.6, 0, 559.2], [0, 0, 559.2], [0, 548.8, 559.2], [556, 548.8, 559.2]),
    "green": ([0, 0, 559.2], [0, 0, 0], [0, 548.8, 0], [0, 548.8, 559.2]),
    "red": ([552.8, 0, 0], [549.6, 0, 559.2], [556, 548.8, 559.2], [556, 548.8, 0]),
    "light": ([343, 548.7, 227], [343, 548.7, 332], [213, 548.7, 332], [213, 548.7, 227]),
}
_SHORT_BLOCK = [
    ([130, 165, 65], [82, 165, 225], [240, 165, 272], [290, 165, 114]),
    ([290, 0, 114], [290, 165, 114], [240, 165, 272], [240, 0, 272]),
    ([130, 0, 65], [130, 165, 65], [290, 165, 114], [290, 0, 114]),
    ([82, 0, 225], [82, 165, 225], [130, 165, 65], [130, 0, 65]),
    ([240, 0, 272], [240, 165, 272], [82, 165, 225], [82, 0, 225]),
]
_TALL_BLOCK = [
    ([423, 330, 247], [265, 330, 296], [314, 330, 456], [472, 330, 406]),
    ([423, 0, 247], [423, 330, 247], [472, 330, 406], [472, 0, 406]),
    ([472, 0, 406], [472, 330, 406], [314, 330, 456], [314, 0, 456]),
    ([314, 0, 456], [314, 330, 456], [265, 330, 296], [265, 0, 296]),
    ([265, 0, 296], [265, 330, 296], [423, 330, 247], [423, 0, 247]),
]


def _quads_mesh(quads, bsdf, emitter=None) -> dict:
    verts, faces = [], []
    for q in quads:
        b = len(verts)
        verts += [np.array(v, float) / 1000.0 for v in q]
        faces += [[b, b + 1, b + 2], [b, b + 2, b + 3]]
    d = {"type": "trimesh", "vertices": np.array(verts), "faces": np.array(faces), "bsdf": bsdf}
    if emitter:
        d["emitter"] = emitter
    return d


def _diffuse(rgb, twosided=True) -> dict:
    b = {"type": "diffuse", "reflectance": {"type": "rgb", "value": rgb}}
    return {"type": "twosided", "bsdf": b} if twosided else b


def _sensor(width, height, fov, to_world, spp, rfilter="tent") -> dict:
    return {
        "type": "perspective", "fov": fov, "fov_axis": "x", "to_world": to_world,
        "film": {"type": "hdrfilm", "width": width, "height": height, "rfilter": {"type": rfilter}},
        "sampler": {"type": "independent", "sample_count": spp},
    }


def _look_at(origin, target, up):
    from .transforms import look_at

    return look_at(origin, target, up)


def cornell_box(glossy: bool = False, width=512, height=512, spp=16, max_depth=-1, light_scale=1.0) -> dict:
    """light_scale > 1 enlarges the light about its centre (same radiance), for tests that need
    BSDF sampling to find it often."""
    fov = math.degrees(2 * math.atan(12.5 / 35.0))
    cam = _look_at([0.278, 0.273, -0.800], [0.278, 0.273, 0.0], [0, 1, 0])
    white = _diffuse(WHITE)
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": _sensor(width, height, fov, cam, spp),
        "floor": _quads_mesh([_QUADS["floor"]], white),
        "ceiling": _quads_mesh([_QUADS["ceiling"]], white),
        "back": _quads_mesh([_QUADS["back"]], white),
        "green": _quads_mesh([_QUADS["green"]], _diffuse(GREEN)),
        "red": _quads_mesh([_QUADS["red"]], _diffuse(RED)),
        "short": _quads_mesh(_SHORT_BLOCK, white),
        "tall": _quads_mesh(_TALL_BLOCK, white),
        "light": _quads_mesh([_scaled_quad(_QUADS["light"], light_scale)], _diffuse([0, 0, 0]),
                             {"type": "area", "radiance": {"type": "rgb", "value": LIGHT}}),
    }
    if glossy:
        scene["tall"]["bsdf"] = {"type": "twosided", "bsdf": {
            "type": "roughconductor", "distribution": "ggx", "alpha": 0.25,
            "eta": {"type": "rgb", "value": [0.2004, 0.9240, 1.1022]},
            "k": {"type": "rgb", "value": [3.9129, 2.4528, 2.1422]}}}
        scene["back"]["bsdf"] = {"type": "twosided", "bsdf": {
            "type": "roughconductor", "distribution": "beckmann", "alpha": 0.4,
            "specular_reflectance": {"type": "rgb", "value": WHITE}}}
    return scene


def _scaled_quad(quad, s):
    q = np.array(quad, float)
    c = q.mean(0)
    return list(c + (q - c) * s)


ANALYTIC_MAX_DEPTH = 64  # default max_depth of the closed spheres (see the module docstring)


def furnace(width=32, height=32, spp=16, max_depth=ANALYTIC_MAX_DEPTH, albedo=0.5, radiance=0.5) -> dict:
    """Closed emitting sphere: L = radiance * (1 - albedo^max_depth) / (1 - albedo) everywhere
    (1 - 0.5^64 at the defaults; max_depth=-1: unbounded, L = 1)."""
    return sphere_cap(width, height, spp, max_depth, albedo, radiance, phi=1.0)


def sphere_cap(width=32, height=32, spp=16, max_depth=ANALYTIC_MAX_DEPTH, albedo=0.5, radiance=1.0, phi=0.05,
               segments=128) -> dict:
    """Unit sphere seen from inside; the cap z > 1 - 2 phi emits `radiance` (phi = 1: all).

    max_depth defaults to 64 (the truncation drops albedo^63 of the unbounded radiance;
    `sphere_cap_radiance` gives the value for any depth); -1 is unbounded."""
    cam = _look_at([0, 0, 0.5], [0, 0, -1], [0, 1, 0])  # looks away from the cap
    bsdf = {"type": "diffuse", "reflectance": {"type": "rgb", "value": [albedo] * 3}}
    emit = {"type": "area", "radiance": {"type": "rgb", "value": [radiance] * 3}}
    scene = {
        "type": "scene",
        "integrator": {"type": "path", "max_depth": max_depth},
        "sensor": _sensor(width, height, 60.0, cam, spp, "box"),
    }
    # Flat-shaded facets: with interpolated shading normals a closed enclosure no longer
    # conserves energy exactly, and the analytic answers below assume it does.
    if phi >= 1.0:
        scene["sphere"] = {"type": "trimesh", **_sphere_band(segments, -1.0, 1.0), "bsdf": bsdf, "emitter": emit}
        return scene
    scene["wall"] = {"type": "trimesh", **_sphere_band(segments, -1.0, 1 - 2 * phi), "bsdf": bsdf}
    scene["cap"] = {"type": "trimesh", **_sphere_band(segments, 1 - 2 * phi, 1.0), "bsdf": bsdf, "emitter": emit}
    return scene


def _sphere_band(segments: int, z0: float, z1: float) -> dict:
    """Inward-facing triangles of the unit sphere between heights z0 and z1 (equal-area rings)."""
    n_phi, n_z = 2 * segments, segments
    zs = np.linspace(z0, z1, max(2, int(round(n_z * (z1 - z0) / 2)) + 1))
    ph = np.linspace(0, 2 * np.pi, n_phi + 1)
    verts, faces = [], []
    r = np.sqrt(np.maximum(0, 1 - zs ** 2))
    for i, z in enumerate(zs):
        for p in ph:
            verts.append([r[i] * np.cos(p), r[i] * np.sin(p), z])
    idx = lambda i, j: i * (n_phi + 1) + j  # noqa: E731
    for i in range(len(zs) - 1):
        for j in range(n_phi):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            if r[i] > 0:
                faces.append([a, d, b])
            if r[i + 1] > 0:
                faces.append([b, d, c])
    v, f = np.array(verts), np.array(faces)
    p = v[f]
    n = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    inward = np.einsum("ij,ij->i", n, p.mean(1)) < 0
    f[~inward] = f[~inward][:, ::-1]
    return {"vertices": v, "faces": f}


def sphere_cap_radiance(albedo: float, radiance: float, phi: float, max_depth: int) -> float:
    """A1: L = rho * phi * Le * sum_{j<n} rho^j at non-emitting points, n = max_depth - 1 bounces."""
    if max_depth < 0:
        return albedo * phi * radiance / (1 - albedo)
    n = max_depth - 1
    return albedo * phi * radiance * sum(albedo ** j for j in range(n))


def many_lights(width=256, height=256, spp=16, max_depth=-1, count=400, seed=7, saturation=1.0) -> dict:
    """The Cornell room without its light, lit by `count` small emissive triangles of random
    colour and power that hang 3-7 cm below the ceiling or stand 3-7 cm off the side walls above
    the blocks, facing into the room, 1 cm or more from every other surface (ReSTIR DI's
    many-light benchmark). Deterministic for a seed.

    The gap matters for measurements: an emitter lying flat on a wall (an earlier version had
    0.5 mm) lights the wall right beside it at grazing angles from millimetres away, where
    G = cos cos / d^2 has no useful bound; every estimator then has rare, enormous samples there,
    and relMSE figures are dominated by a few pixels and change from seed to seed."""
    scene = cornell_box(width=width, height=height, spp=spp, max_depth=max_depth)
    del scene["light"]
    rng = np.random.default_rng(seed)
    for i in range(count):
        wall = rng.integers(0, 3)  # ceiling, left wall, right wall
        a, b = rng.uniform(0.08, 0.46, 2)
        size = rng.uniform(0.004, 0.012)
        gap = rng.uniform(0.03, 0.07)
        if wall == 0:
            p = np.array([a, 0.5488 - gap, b])
            tri = [p, p + [size, 0, 0], p + [0, 0, size]]
        elif wall == 1:
            p = np.array([0.5525 - gap, 0.34 + 0.4 * (a - 0.08), b])
            tri = [p, p + [0, 0, size], p + [0, size, 0]]
        else:
            p = np.array([gap, 0.34 + 0.4 * (a - 0.08), b])
            tri = [p, p + [0, size, 0], p + [0, 0, size]]
        hue = rng.uniform(0.2, 1.0, 3)
        color = (saturation * hue + (1 - saturation) * hue.mean()) * rng.uniform(50, 400)
        scene[f"light{i}"] = {"type": "trimesh", "vertices": np.array(tri), "faces": np.array([[0, 1, 2]]),
                              "bsdf": _diffuse([0, 0, 0]),
                              "emitter": {"type": "area", "radiance": {"type": "rgb", "value": list(color)}}}
    return scene


def many_delta_lights(width=256, height=256, spp=16, max_depth=-1, count=300, seed=11) -> dict:
    """The Cornell room without its light, lit by `count` delta lights of random colour and power:
    two thirds point lights, hanging 10-20 cm below the ceiling or standing 10-20 cm off the side
    walls, and one third spot lights 10-20 cm below the ceiling, each aimed at a random point of the
    floor with a cone of 20-50 degrees (Mitsuba 3's falloff; ReSTIR DI's many-light benchmark made
    of the lights engines use). Deterministic for a seed. The gap keeps every light at least
    10 cm from a surface, so I / d^2 stays within 100 I (the many-lights room's reason, there for
    G's 1 / d^2)."""
    scene = cornell_box(width=width, height=height, spp=spp, max_depth=max_depth)
    del scene["light"]
    rng = np.random.default_rng(seed)
    for i in range(count):
        a, b = rng.uniform(0.1, 0.45, 2)
        gap = rng.uniform(0.1, 0.2)
        hue = rng.uniform(0.2, 1.0, 3)
        color = hue * rng.uniform(2e-4, 1.3e-3)  # about the Cornell box's direct light in all
        if i % 3 == 2:  # a spot under the ceiling, aimed at the floor
            p = np.array([a, 0.5488 - gap, b])
            target = np.array([rng.uniform(0.05, 0.5), 0.0, rng.uniform(0.05, 0.5)])
            cutoff = rng.uniform(20, 50)
            scene[f"light{i}"] = {"type": "spot", "to_world": _look_at(p, target, [0, 0, 1]),
                                  "cutoff_angle": float(cutoff), "beam_width": float(cutoff * rng.uniform(0.3, 0.9)),
                                  "intensity": {"type": "rgb", "value": list(color * 4.0)}}
            continue
        wall = rng.integers(0, 3)  # ceiling, left wall, right wall
        if wall == 0:
            p = np.array([a, 0.5488 - gap, b])
        elif wall == 1:
            p = np.array([0.5525 - gap, 0.34 + 0.4 * (a - 0.1), b])
        else:
            p = np.array([gap, 0.34 + 0.4 * (a - 0.1), b])
        scene[f"light{i}"] = {"type": "point", "position": list(p), "intensity": {"type": "rgb", "value": list(color)}}
    return scene


def indirect_room(width=256, height=256, spp=16, max_depth=-1, radiance_scale=4.0) -> dict:
    """The Cornell room lit almost only indirectly (ReSTIR PT's test and benchmark scene): its
    light, 1.5x larger and `radiance_scale` x brighter, hangs 6 cm below the ceiling facing up,
    above a slightly larger baffle, so that neither the camera nor the floor, walls and blocks
    see it; only the ceiling is lit directly. Glossy surfaces: a GGX rough-conductor floor
    (alpha 0.3), a rough-plastic tall block (a sharp GGX coat, alpha 0.02, linear roughness 0.14,
    over a white base: two smooth lobes, one rough and one not, so ReSTIR PT's reconnection
    criteria depend on the lobe a path samples there), a Beckmann rough-conductor back wall
    (alpha 0.4)."""
    scene = cornell_box(width=width, height=height, spp=spp, max_depth=max_depth)
    y = 0.5488 - 0.06
    light = np.array(_scaled_quad(_QUADS["light"], 1.5)) / 1000.0
    light[:, 1] = y
    up = light[::-1]  # reversed winding: the emitting side faces the ceiling
    baffle = np.array(_scaled_quad(_QUADS["light"], 1.8)) / 1000.0
    baffle[:, 1] = y - 0.005
    scene["light"] = _quads_mesh([list(up * 1000.0)], _diffuse([0, 0, 0], twosided=False),
                                 {"type": "area", "radiance": {"type": "rgb", "value": [v * radiance_scale
                                                                                        for v in LIGHT]}})
    scene["baffle"] = _quads_mesh([list(baffle * 1000.0)], _diffuse(WHITE))
    scene["floor"]["bsdf"] = {"type": "roughconductor", "distribution": "ggx", "alpha": 0.3,
                              "specular_reflectance": {"type": "rgb", "value": WHITE}}
    scene["tall"]["bsdf"] = {"type": "roughplastic", "distribution": "ggx", "alpha": 0.02,
                             "diffuse_reflectance": {"type": "rgb", "value": WHITE}}
    scene["back"]["bsdf"] = {"type": "twosided", "bsdf": {
        "type": "roughconductor", "distribution": "beckmann", "alpha": 0.4,
        "specular_reflectance": {"type": "rgb", "value": WHITE}}}
    return scene


ANIMATED_FRAMES = 64  # the animated Cornell box's period


def cornell_box_animated(width=512, height=512, spp=16, max_depth=-1) -> dict:
    """The Cornell box in motion over 64 frames (then it holds its last pose): the short block
    slides across the floor toward the red wall and back; the light swings along x, and is
    switched off for frames 24 to 31 (docs/guide/animation.md)."""
    from .animation import Animation, Motion

    scene = cornell_box(width=width, height=height, spp=spp, max_depth=max_depth)
    n = ANIMATED_FRAMES
    scene["_animation"] = Animation({
        "short": Motion(translation=([0, n // 2, n], [[0, 0, 0], [0.22, 0, -0.06], [0, 0, 0]])),
        "light": Motion(translation=([0, n // 4, 3 * n // 4, n], [[0, 0, 0], [0.1, 0, 0], [-0.1, 0, 0], [0, 0, 0]]),
                        emission=([0, 24, 32], [[1.0], [0.0], [1.0]], "step")),
    }, frames=n)
    return scene


BUILTINS = {
    "cornell-box": cornell_box,
    "cornell-box-animated": cornell_box_animated,
    "cornell-box-glossy": lambda **kw: cornell_box(glossy=True, **kw),
    "furnace": furnace,
    "sphere-cap": sphere_cap,
    "many-lights": many_lights,
    "many-delta-lights": many_delta_lights,
    "indirect-room": indirect_room,
}


# One line each, for `restir render --help`.
BUILTIN_DESCRIPTIONS = {
    "cornell-box": "the Cornell box (measured geometry, RGB materials), 512x512, 16 spp, unbounded depth",
    "cornell-box-glossy": "the Cornell box with a rough-conductor tall block and Beckmann back wall",
    "cornell-box-animated": "the Cornell box in motion over 64 frames: the short block slides, the light swings and "
                            "is off for frames 24-31",
    "furnace": f"closed emitting sphere, albedo 0.5: every pixel 1 - 0.5^max_depth; max_depth "
               f"{ANALYTIC_MAX_DEPTH} by default (truncates 0.5^{ANALYTIC_MAX_DEPTH}; -1: unbounded, 1)",
    "sphere-cap": f"closed diffuse sphere lit by an emissive cap, analytic radiance "
                  f"(docs/validation.md#level-2-analytic-scenes-and-external-references); "
                  f"max_depth {ANALYTIC_MAX_DEPTH} by default (truncates 0.5^{ANALYTIC_MAX_DEPTH - 1}; -1: unbounded)",
    "many-lights": "the Cornell room lit by 400 small coloured emitters (ReSTIR DI's benchmark)",
    "many-delta-lights": "the Cornell room lit by 300 coloured point and spot lights (ReSTIR DI's benchmark, delta lights)",
    "indirect-room": "the Cornell room lit almost only indirectly (light hidden, facing the ceiling), glossy "
                     "floor, block and wall (ReSTIR PT's benchmark)",
}


def builtin_scene(name: str, **kwargs) -> dict:
    if name not in BUILTINS:
        raise SceneError(f"unknown builtin scene '{name}' (available: {', '.join(sorted(BUILTINS))})", f"builtin:{name}")
    return BUILTINS[name](**kwargs)
