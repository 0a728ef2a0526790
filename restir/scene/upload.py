"""Host Scene -> device structs (SceneDevice, Camera). Keeps the Warp arrays alive."""
import copy

import numpy as np
import warp as wp

from ..device.bsdf import Material
from ..device.bsdfs.registry import MATERIAL_KINDS
from ..device.bump import PERTURB_HEIGHT, PERTURB_NORMAL, Bump
from ..device.camera import Camera
from ..device.delta_lights import DeltaLight
from ..device.scene_device import SceneDevice, vec8i
from ..device.textures import (TEX_BITMAP, TEX_CHECKERBOARD, TEX_FILTER_BILINEAR, TEX_FILTER_NEAREST, TEX_WRAP_CLAMP,
                               TEX_WRAP_MIRROR, TEX_WRAP_REPEAT, Texture)
from ..device.types import (DELTA_DIRECTIONAL, DELTA_POINT, DELTA_SPOT, ENV_CONSTANT, ENV_MAP, ENV_NONE,
                            FALLOFF_LINEAR_ANGLE, FALLOFF_SMOOTHSTEP, FALLOFF_SQUARED_RAMP, FILTER_BOX, FILTER_GAUSSIAN,
                            FILTER_TENT, LIGHT_DELTA_BASE,
                            MAT_CONDUCTOR, MAT_DIELECTRIC, MAT_DIFFUSE, MAT_PLASTIC, MAT_ROUGHCONDUCTOR, MAT_ROUGHPLASTIC,
                            MAT_ROUGHDIELECTRIC, MAT_THINDIELECTRIC, MICROFACET_BECKMANN, MICROFACET_GGX)
from .light_tables import alias_table, cdf_1d, env_tables
from .animation import moving_objects, posed_delta_light, posed_object, posed_scene
from .scene import TEXTURED_PARAMETERS, Scene
from .transforms import transform_points

MATERIAL_KIND = {k.name: k.kind for k in MATERIAL_KINDS}
MATERIAL_KIND["mixture"] = MAT_DIFFUSE  # never evaluated: scene_device.material_index_at picks one of its two
FILTER_KIND = {"box": FILTER_BOX, "tent": FILTER_TENT, "gaussian": FILTER_GAUSSIAN}
FILTER_TABLE_BINS = 256


def material_struct(m, device="cpu") -> Material:
    """The caller keeps `s.coat_transmittance` alive (DeviceScene does, via _arrays)."""
    s = Material()
    s.kind = int(MATERIAL_KIND[m.kind])
    s.twosided = int(m.twosided)
    s.reflectance = wp.vec3(*m.reflectance)
    s.specular_reflectance = wp.vec3(*m.specular_reflectance)
    s.specular_transmittance = wp.vec3(*m.specular_transmittance)
    s.eta = wp.vec3(*m.eta)
    s.k = wp.vec3(*m.k)
    s.ior = float(m.ior)
    s.distribution = int(MICROFACET_GGX if m.distribution == "ggx" else MICROFACET_BECKMANN)
    s.alpha_u = float(m.alpha_u)
    s.alpha_v = float(m.alpha_v)
    s.specular_sampling_weight = float(m.specular_sampling_weight)
    s.fdr_int = float(m.fdr_int)
    s.nonlinear = int(m.nonlinear)
    s.bumped = int(m.bump is not None)
    s.masked = int(m.masked)
    s.opacity = float(m.opacity)
    s.roughness_remap = int(m.roughness_remap)
    s.metallic = float(m.metallic)
    table = m.coat_transmittance if m.coat_transmittance is not None else np.ones(2)
    s.coat_transmittance = wp.array(np.asarray(table, np.float32), dtype=float, device=device)
    return s


def delta_light_struct(d) -> DeltaLight:
    """A delta light (scene.delta_lights.DeltaLightDesc) as the device reads it."""
    s = DeltaLight()
    s.kind = int({"point": DELTA_POINT, "spot": DELTA_SPOT, "directional": DELTA_DIRECTIONAL}[d.kind])
    s.p = wp.vec3(*np.asarray(d.position, np.float32))
    s.axis = wp.vec3(*np.asarray(d.axis, np.float32))
    s.I = wp.vec3(*np.asarray(d.intensity, np.float32))
    s.falloff = int({"linear_angle": FALLOFF_LINEAR_ANGLE, "smoothstep": FALLOFF_SMOOTHSTEP,
                     "squared_ramp": FALLOFF_SQUARED_RAMP}[d.falloff])
    s.inner, s.outer = float(d.inner), float(d.outer)
    s.cos_inner, s.cos_outer = float(np.cos(d.inner)), float(np.cos(d.outer))
    return s


def bump_struct(b) -> Bump:
    """A material's bump or normal map (scene.BumpDesc or None) as the device reads it (device/bump.py)."""
    s = Bump()
    s.texture = -1 if b is None else int(b.texture)
    if b is not None:
        s.kind = int(PERTURB_NORMAL if b.kind == "normal" else PERTURB_HEIGHT)
        s.scale = float(b.scale)
        s.uv_handed = int(b.uv_handed)
        s.flip_invalid = int(b.flip_invalid_normals)
        s.shadowing = int(b.use_shadowing_function)
    return s


def _new_slot() -> dict:
    """One frame's device data: its per-triangle arrays (kept from frame to frame, written where
    things move), its light tables (made each frame), BVH, Embree scene, the frame and the objects
    moved then."""
    return {"arrays": [], "tables": [], "mesh": None, "embree": None, "frame": None, "moved": set(),
            "normals": None, "tangents": None, "tri_emission": None, "tri_light_pdf": None}


class DeviceScene:
    """Owns every device array of one scene; `.scene` and `.camera` are the kernel arguments."""

    def __init__(self, scene: Scene, device: str = "cpu", tracer: str = "auto", jitter: bool = True):
        """tracer: "embree" (CPU only), "warp", or "auto" (Embree on the CPU when available);
        jitter: False puts every primary ray through its pixel centre (Camera.jitter)."""
        self.host = scene
        self.device = device
        self.tracer = tracer
        self.jitter = jitter
        self._arrays = []
        self.scene = self._scene_struct(scene)
        self.camera = self.camera_struct(scene.camera)

    def _arr(self, data, dtype):
        a = wp.array(data, dtype=dtype, device=self.device)
        self._arrays.append(a)
        return a

    def _scene_struct(self, sc: Scene) -> SceneDevice:
        s = SceneDevice()
        self._slot = 0
        self._slots = [_new_slot(), _new_slot()]
        self.frame = 0
        # the triangles that can emit (an animation scales emission, never lights a triangle up) and
        # the rest pose's bounding radius (a directional light's power: its selection probability)
        self._emitters = np.nonzero(np.any(sc.tri_emission > 0, axis=1))[0].astype(np.int32)
        self._radius = sc.bounding_radius() if sc.delta_lights else 0.0
        posed = posed_scene(sc, 0) if sc.animation is not None else sc
        self._geometry(s, posed, self._slots[0])
        self.tracer_used = "embree" if self.embree is not None else "warp"
        s.uvs = self._arr(sc.uvs.reshape(-1, 2).astype(np.float32), wp.vec2)
        s.tri_smooth = self._arr(sc.tri_smooth.astype(np.int32), wp.int32)
        s.tri_material = self._arr(sc.tri_material.astype(np.int32), wp.int32)
        twosided = sc.tri_emit_twosided
        s.num_twosided_emitters = 0 if twosided is None else int(np.count_nonzero(twosided))
        s.tri_emit_twosided = self._arr(np.asarray(twosided if s.num_twosided_emitters else [0], np.int32), wp.int32)
        structs = [material_struct(m, self.device) for m in sc.materials]
        self._arrays += [ms.coat_transmittance for ms in structs]
        s.materials = wp.array(structs, dtype=Material, device=self.device)
        self._arrays.append(s.materials)
        slots = np.full((len(sc.materials), 8), -1, np.int32)
        for i, m in enumerate(sc.materials):
            slots[i, :len(TEXTURED_PARAMETERS)] = [m.textures.get(p, -1) for p in TEXTURED_PARAMETERS]
        s.material_textures = self._arr(slots, vec8i)
        s.material_mix = self._arr(np.array([m.mix if m.mix is not None else (-1, -1) for m in sc.materials],
                                            np.int32).reshape(-1, 2), wp.vec2i)
        s.material_mix_amount = self._arr(np.array([m.mix_amount for m in sc.materials], np.float32), float)
        s.num_mixtures = int(sum(m.mix is not None for m in sc.materials))
        s.material_bump = self._arr([bump_struct(m.bump) for m in sc.materials] or [bump_struct(None)], Bump)
        self._lights(s, posed, self._slots[0])
        if sc.animation is not None:
            self._slots[0]["frame"] = 0
            self._slots[0]["moved"] = moving_objects(sc, sc.animation.state(0))

        s.env_kind = int({"none": ENV_NONE, "constant": ENV_CONSTANT, "envmap": ENV_MAP}[sc.env_kind])
        s.env_radiance = wp.vec3(*sc.env_radiance)
        rot = np.asarray(sc.env_to_world, np.float64)
        s.env_to_world = wp.mat33(*rot.astype(np.float32).reshape(-1))
        s.env_to_local = wp.mat33(*np.linalg.inv(rot).astype(np.float32).reshape(-1))
        if sc.env_kind == "envmap":
            img = sc.env_image.astype(np.float32)
            h, w = img.shape[:2]
            marginal, cond = env_tables(img @ np.array([0.2126, 0.7152, 0.0722], np.float32))
            s.env_width, s.env_height = w, h
            s.env_pixels = self._arr(img.reshape(-1, 3), wp.vec3)
            s.env_marginal_cdf = self._arr(marginal, float)
            s.env_conditional_cdf = self._arr(cond, float)
        else:
            s.env_width = s.env_height = 1
            s.env_pixels = self._arr(np.zeros((1, 3), np.float32), wp.vec3)
            s.env_marginal_cdf = self._arr(np.array([0.0, 1.0], np.float32), float)
            s.env_conditional_cdf = self._arr(np.array([0.0, 1.0], np.float32), float)
        self._env_select(s, sc)

        s.textures, s.tex_pixels = self._textures(sc.textures)
        return s

    def _slot_arr(self, slot: dict, data, dtype, kind: str = "arrays"):
        a = wp.array(data, dtype=dtype, device=self.device)
        slot[kind].append(a)
        return a

    def _geometry(self, s: SceneDevice, sc: Scene, slot: dict) -> None:
        """The frame's triangles into `slot` (its arrays replaced; its BVH refitted where it has
        one of the same size, its Embree scene built again) and into s."""
        slot["arrays"] = []
        pts = sc.positions.reshape(-1, 3).astype(np.float32)
        mesh = slot["mesh"]
        if mesh is not None and mesh.points.shape[0] == len(pts):
            mesh.points.assign(pts)
            if slot["embree"] is None:  # with Embree (the CPU) Warp's BVH is never traced
                mesh.refit()
        else:
            mesh = slot["mesh"] = wp.Mesh(points=wp.array(pts, dtype=wp.vec3, device=self.device),
                                          indices=wp.array(np.arange(len(pts), dtype=np.int32), dtype=wp.int32,
                                                           device=self.device))
        self.mesh = mesh
        s.mesh = mesh.id
        s.embree_scene = s.embree_intersect = s.embree_occluded = wp.uint64(0)
        if wp.get_device(self.device).is_cpu and self.tracer in ("auto", "embree"):
            from ..embree import EmbreeScene, library

            if library() is not None:
                moving = moving_objects(self.host, self.host.animation.state(self.frame)) if self.animated else ()
                slot["embree"] = EmbreeScene(sc.positions, sorted(self.host.objects[n] for n in moving))
            elif self.tracer == "embree":
                raise RuntimeError("Embree was requested but is not available (pip install embreex)")
        elif self.tracer == "embree":
            raise RuntimeError("Embree traces on the CPU only")
        self.embree = slot["embree"]
        if self.embree is not None:
            s.embree_scene = wp.uint64(self.embree.scene)
            s.embree_intersect = wp.uint64(self.embree.intersect_fn)
            s.embree_occluded = wp.uint64(self.embree.occluded_fn)
        s.positions = mesh.points
        s.normals = slot["normals"] = self._slot_arr(slot, sc.normals.reshape(-1, 3).astype(np.float32), wp.vec3)
        s.has_tangents = int(sc.tangents is not None)
        s.tangents = slot["tangents"] = self._slot_arr(slot, sc.tangents.reshape(-1, 4) if sc.tangents is not None
                                                       else np.zeros((1, 4), np.float32), wp.vec4)

    def _lights(self, s: SceneDevice, sc: Scene, slot: dict) -> None:
        """The lights of the posed scene sc (its every triangle's emission uploaded: the slot's first
        frame)."""
        E = self._emitters
        s.tri_emission = slot["tri_emission"] = self._slot_arr(slot, sc.tri_emission.astype(np.float32), wp.vec3)
        slot["tri_light_pdf"] = None
        self._light_tables(s, slot, sc.positions[E], sc.tri_emission[E], sc.delta_lights)

    def _light_tables(self, s: SceneDevice, slot: dict, pos: np.ndarray, emission: np.ndarray, deltas_of) -> None:
        """One alias table over the emissive triangles, then the delta lights, by power, from the
        frame's emitters (their positions and emission, rows of self._emitters) and delta lights,
        into `slot` and s; the per-triangle pdf made (the slot's first frame) or written at the
        emitters alone (the other triangles never emit)."""
        E = self._emitters
        p = pos.astype(np.float64)
        area = 0.5 * np.linalg.norm(np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0]), axis=1)
        lum = emission @ np.array([0.2126, 0.7152, 0.0722])
        twosided = self.host.tri_emit_twosided
        sides = 1.0 if twosided is None else 1.0 + twosided[E]
        power = np.maximum(lum, 0) * area * sides  # Scene.light_power at the emitters
        on = np.nonzero(power > 0)[0]
        lights = E[on]
        delta_power = np.array([d.power(self._radius) for d in deltas_of], np.float64)
        deltas = np.nonzero(delta_power > 0)[0].astype(np.int32)
        pdf = np.zeros(len(E), np.float32)
        delta_pmf = np.zeros(max(len(deltas_of), 1), np.float32)
        entries = np.concatenate([lights, LIGHT_DELTA_BASE - deltas]).astype(np.int32)
        if len(entries):
            prob, alias, pmf = alias_table(np.concatenate([power[on], delta_power[deltas]]))
            pdf[on] = pmf[:len(lights)] / area[on]
            delta_pmf[deltas] = pmf[len(lights):]
        else:
            prob, alias = np.ones(1, np.float32), np.zeros(1, np.int32)
        if slot["tri_light_pdf"] is None:
            tri_pdf = np.zeros(self.host.num_triangles, np.float32)
            tri_pdf[E] = pdf
            slot["tri_light_pdf"] = self._slot_arr(slot, tri_pdf, float)
        else:
            self._write_at(slot["tri_light_pdf"], E, pdf, float)
        s.tri_light_pdf = slot["tri_light_pdf"]
        slot["tables"] = []  # the slot's last frame's tables: no struct in use reads them any more
        s.light_tri = self._slot_arr(slot, entries if len(entries) else np.zeros(1, np.int32), wp.int32, "tables")
        s.light_prob = self._slot_arr(slot, prob, float, "tables")
        s.light_alias = self._slot_arr(slot, alias, wp.int32, "tables")
        s.num_tri_lights = int(len(lights))
        s.delta_lights = self._slot_arr(slot, [delta_light_struct(d) for d in deltas_of] or [DeltaLight()],
                                        DeltaLight, "tables")
        s.delta_light_pmf = self._slot_arr(slot, delta_pmf, float, "tables")
        s.num_delta_lights = int(len(deltas))
        self._has_lights = bool(len(entries))

    def _write_at(self, dest, index: np.ndarray, values: np.ndarray, dtype) -> None:
        """dest[index] = values on the device, one copy per run of consecutive indices."""
        if not len(index):
            return
        src = wp.array(values, dtype=dtype, device=self.device)
        breaks = np.nonzero(np.diff(index) != 1)[0] + 1
        for run in np.split(np.arange(len(index)), breaks):
            wp.copy(dest, src, dest_offset=int(index[run[0]]), src_offset=int(run[0]), count=len(run))

    def _env_select(self, s: SceneDevice, sc: Scene) -> None:
        has_env = sc.env_kind != "none"
        s.env_select_prob = float(1.0 if has_env and not self._has_lights else (0.5 if has_env else 0.0))

    # ------------------------------------------------------------------ animation
    def with_current_lights(self, prev: SceneDevice) -> SceneDevice:
        """A fault injection (ReSTIR DI's mutation previous_lights_dropped): the previous frame's
        scene `prev` with this frame's lights (the emitters' triangles where they are now, their
        emission, the delta lights, the light tables), as a renderer that keeps the previous
        geometry but not the previous lights would have it."""
        s = SceneDevice()
        for name in SceneDevice.vars:
            setattr(s, name, getattr(prev, name))
        for name in ("tri_emission", "light_tri", "light_prob", "light_alias", "num_tri_lights", "tri_light_pdf",
                     "delta_lights", "delta_light_pmf", "num_delta_lights", "env_select_prob"):
            setattr(s, name, getattr(self.scene, name))
        emitters = np.zeros(self.host.num_triangles, bool)
        emitters[self._emitters] = True
        pts = np.where(np.repeat(emitters, 3)[:, None], self.scene.positions.numpy(), prev.positions.numpy())
        s.positions = wp.array(pts, dtype=wp.vec3, device=self.device)
        self._mutant_positions = s.positions  # kept alive while the struct is in use
        return s

    @property
    def animated(self) -> bool:
        return self.host.animation is not None

    def set_frame(self, frame: int) -> None:
        """Make `scene` the scene at `frame` (an animated scene; a static one has one scene). The
        struct of the frame before stays valid (its arrays live in the other of two slots) until
        the frame after this one is set: an integrator keeps it as the previous sample's domain.

        A slot's first frame uploads everything. Later frames into the same slot (two frames on)
        write only the objects that move at this frame or moved at the slot's last frame, refit
        their ray-tracing structures (Embree's per-geometry BVHs of a dynamic scene, or Warp's
        BVH), and write the light tables' entries at the emitters: the rest of the scene is the
        same in every frame."""
        if not self.animated or frame == self.frame:
            return
        s = SceneDevice()
        for name in SceneDevice.vars:
            setattr(s, name, getattr(self.scene, name))
        self._slot = 1 - self._slot
        slot = self._slots[self._slot]
        self.frame = frame
        host = self.host
        state = host.animation.state(frame)
        moving = moving_objects(host, state)
        if slot["frame"] is None or not self._update_geometry(s, slot, state, moving | slot["moved"]):
            posed = posed_scene(host, frame)
            self._geometry(s, posed, slot)
            self._lights(s, posed, slot)
        else:
            pos, emission, deltas = self._posed_lights(state)
            s.tri_emission = slot["tri_emission"]
            self._write_at(s.tri_emission, self._emitters, emission.astype(np.float32), wp.vec3)
            self._light_tables(s, slot, pos, emission, deltas)
        self._env_select(s, host)
        slot["frame"], slot["moved"] = frame, moving
        self.scene = s

    def _update_geometry(self, s: SceneDevice, slot: dict, state: dict, names: set) -> bool:
        """Write the named objects' triangles at this frame into the slot's arrays and refit; False
        where the slot's Embree scene does not hold one of them apart (it is then built again)."""
        host = self.host
        parts = {}
        for name in sorted(names):
            lo, hi = host.objects[name]
            m = state.get(name, (None, 1.0))[0]
            if m is not None:
                parts[lo] = (hi, *posed_object(host, name, m, self.frame))
            else:
                tan = host.tangents[lo:hi] if host.tangents is not None else None
                parts[lo] = (hi, host.positions[lo:hi], host.normals[lo:hi], tan)
        embree = slot["embree"]
        if embree is not None and not {(lo, hi) for lo, (hi, *_) in parts.items()} <= set(embree.dynamic):
            return False
        mesh = slot["mesh"]
        for lo, (hi, pos, nrm, tan) in parts.items():
            n = 3 * (hi - lo)
            wp.copy(mesh.points, wp.array(pos.reshape(-1, 3), dtype=wp.vec3, device=self.device), 3 * lo, 0, n)
            wp.copy(slot["normals"], wp.array(nrm.reshape(-1, 3), dtype=wp.vec3, device=self.device), 3 * lo, 0, n)
            if tan is not None:
                wp.copy(slot["tangents"], wp.array(tan.reshape(-1, 4), dtype=wp.vec4, device=self.device), 3 * lo, 0, n)
        if embree is not None:
            embree.update({lo: pos for lo, (hi, pos, *_) in parts.items()})
            s.embree_scene = wp.uint64(embree.scene)
        else:
            mesh.refit()
        self.mesh, self.embree = mesh, embree
        s.mesh, s.positions, s.normals, s.tangents = mesh.id, mesh.points, slot["normals"], slot["tangents"]
        return True

    def _posed_lights(self, state: dict) -> tuple:
        """The emitters' positions and emission (rows of self._emitters) and the delta lights at this
        frame's state."""
        host = self.host
        E = self._emitters
        pos, emission = host.positions[E].copy(), host.tri_emission[E].copy()
        lights = list(host.delta_lights)
        for name, (m, e) in state.items():
            if name in host.objects:
                lo, hi = host.objects[name]
                inside = np.nonzero((E >= lo) & (E < hi))[0]
                if not len(inside):
                    continue
                if m is not None:
                    pos[inside] = transform_points(m, host.positions[E[inside]].reshape(-1, 3)).reshape(-1, 3, 3)
                emission[inside] = host.tri_emission[E[inside]] * e
            else:
                i = host.delta_light_names[name]
                lights[i] = posed_delta_light(lights[i], m, e)
        return pos.astype(np.float32), emission.astype(np.float32), lights

    def _textures(self, descs) -> tuple:
        """The texture records and the packed texels (element 0 a black texel, so the array is
        never empty)."""
        texels, records, off = [np.zeros((1, 3), np.float32)], [], 1
        for d in descs:
            t = Texture()
            t.kind = TEX_CHECKERBOARD if d.kind == "checkerboard" else TEX_BITMAP
            t.to_uv = wp.mat33(*d.to_uv.astype(np.float32).reshape(-1))
            t.offset, t.width, t.height = off, 1, 1
            if d.image is not None:
                t.height, t.width = int(d.image.shape[0]), int(d.image.shape[1])
                texels.append(d.image.reshape(-1, 3).astype(np.float32))
                off += t.width * t.height
            t.filter = TEX_FILTER_NEAREST if d.filter == "nearest" else TEX_FILTER_BILINEAR
            t.wrap = {"repeat": TEX_WRAP_REPEAT, "mirror": TEX_WRAP_MIRROR, "clamp": TEX_WRAP_CLAMP}[d.wrap]
            t.color0 = wp.vec3(*np.asarray(d.color0, np.float32))
            t.color1 = wp.vec3(*np.asarray(d.color1, np.float32))
            records.append(t)
        if not records:
            records.append(Texture())  # a placeholder: no material refers to it
        records = wp.array(records, dtype=Texture, device=self.device)
        self._arrays.append(records)
        return records, self._arr(np.concatenate(texels), wp.vec3)

    def camera_struct(self, cd) -> Camera:
        c = Camera()
        c.to_world = wp.mat44(*cd.to_world.astype(np.float32).reshape(-1))
        c.to_local = wp.mat44(*np.linalg.inv(cd.to_world).astype(np.float32).reshape(-1))
        tx, ty = cd.tan_half()
        c.tan_half_x, c.tan_half_y = float(tx), float(ty)
        c.width, c.height = int(cd.width), int(cd.height)
        c.filter = int(FILTER_KIND[cd.filter])
        c.filter_radius = float(cd.filter_radius)
        c.filter_stddev = float(cd.filter_stddev)
        n = FILTER_TABLE_BINS
        x = np.linspace(-cd.filter_radius, cd.filter_radius, 16 * n + 1)
        a = -1.0 / (2 * cd.filter_stddev ** 2)
        f = np.maximum(0.0, np.exp(a * x * x) - np.exp(a * cd.filter_radius ** 2))
        fine = 0.5 * (f[1:] + f[:-1]) * (x[1] - x[0])            # trapezoid per fine cell
        bins = fine.reshape(n, 16).sum(1)
        c.filter_cdf = self._arr(cdf_1d(bins).astype(np.float32), float)
        c.filter_bins = n
        c.filter_inv_integral = float(1.0 / bins.sum())
        c.jitter = int(self.jitter)
        c.aperture_radius = float(cd.aperture_radius)
        c.focus_distance = float(cd.focus_distance)
        return c

    def with_camera(self, cd) -> "DeviceScene":
        """This scene's device arrays under another camera (scene.CameraDesc: the viewer's film
        size and field of view), shared rather than uploaded again."""
        out = copy.copy(self)
        out.host = copy.copy(self.host)
        out.host.camera = cd
        out._arrays = list(self._arrays)
        out.camera = out.camera_struct(cd)
        return out

    def camera_at(self, to_world: np.ndarray) -> Camera:
        """The camera with another pose (scripted motion); filter tables are shared."""
        c = Camera()
        base = self.camera
        for name in ("tan_half_x", "tan_half_y", "width", "height", "filter", "filter_radius", "filter_cdf",
                     "filter_bins", "filter_stddev", "filter_inv_integral", "jitter", "aperture_radius",
                     "focus_distance"):
            setattr(c, name, getattr(base, name))
        c.to_world = wp.mat44(*np.asarray(to_world, np.float32).reshape(-1))
        c.to_local = wp.mat44(*np.linalg.inv(to_world).astype(np.float32).reshape(-1))
        return c

    def memory_bytes(self) -> int:
        """Device bytes of the scene's arrays (both frames' geometry and lights of an animated scene)."""
        slots = self._slots if self.animated else self._slots[:1]
        return (sum(a.capacity for a in self._arrays)
                + sum(a.capacity for sl in slots for a in sl["arrays"] + sl["tables"])
                + sum(sl["mesh"].points.capacity + sl["mesh"].indices.capacity for sl in slots if sl["mesh"] is not None))
