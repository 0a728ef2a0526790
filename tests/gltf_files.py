"""glTF 2.0 for the tests: files written with pygltflib (meshes given as vertices and faces, each
its own node, optionally under a matrix; metallic-roughness materials as the specification's
JSON; a perspective camera and KHR_lights_punctual lights), and the specification's BRDF as its
Appendix B writes it (`appendix_b`), which the BSDF and the reader are checked against."""
import math

import numpy as np
import pygltflib as g


def write_gltf(path, meshes, materials, camera=None, lights=(), extensions_required=(), images=(), animations=()):
    """meshes: [(vertices (N, 3), faces (M, 3), material index or None, extras)] where extras may
    hold "normals", "uvs" (N, 2), "tangents" (N, 4), "matrix" (4x4, node transform), "trs"
    ((translation, rotation xyzw, scale): node transform), "parent" (another mesh's index: this
    node becomes its child), "name"; materials: [dict of glTF JSON];
    camera: (world matrix of the camera node (looks down -Z), yfov radians, aspect, name);
    lights: [(light JSON, world matrix of its node or its (translation, rotation, scale))]; images: [PNG bytes];
    animations: [(node, path, times, values, interpolation)], one channel each, all in one animation
    (nodes: the meshes' first, then the camera's, then the lights')."""
    blob = bytearray()
    views, accessors = [], []

    def add(array, kind, target=None, component=g.FLOAT):
        a = np.ascontiguousarray(array, np.uint32 if component == g.UNSIGNED_INT else np.float32)
        while len(blob) % 4:
            blob.append(0)
        views.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=a.nbytes, target=target))
        blob.extend(a.tobytes())
        acc = g.Accessor(bufferView=len(views) - 1, componentType=component, count=len(a), type=kind)
        if kind == g.VEC3 and np.all(np.isfinite(a)):
            acc.min, acc.max = a.min(0).tolist(), a.max(0).tolist()
        accessors.append(acc)
        return len(accessors) - 1

    nodes, gl_meshes = [], []
    for verts, faces, mat, extras in meshes:
        attrs = g.Attributes(POSITION=add(verts, g.VEC3, g.ARRAY_BUFFER))
        if "normals" in extras:
            attrs.NORMAL = add(extras["normals"], g.VEC3, g.ARRAY_BUFFER)
        if "uvs" in extras:
            attrs.TEXCOORD_0 = add(extras["uvs"], g.VEC2, g.ARRAY_BUFFER)
        if "tangents" in extras:
            attrs.TANGENT = add(extras["tangents"], g.VEC4, g.ARRAY_BUFFER)
        idx = add(np.asarray(faces).reshape(-1), g.SCALAR, g.ELEMENT_ARRAY_BUFFER, g.UNSIGNED_INT)
        gl_meshes.append(g.Mesh(primitives=[g.Primitive(attributes=attrs, indices=idx, material=mat)]))
        node = g.Node(mesh=len(gl_meshes) - 1, name=extras.get("name"))
        if "matrix" in extras:
            node.matrix = np.asarray(extras["matrix"], float).T.reshape(-1).tolist()
        if "trs" in extras:
            node.translation, node.rotation, node.scale = (list(map(float, v)) for v in extras["trs"])
        nodes.append(node)
    cameras = []
    if camera is not None:
        m, yfov, aspect, name = camera
        cameras.append(g.Camera(type="perspective", perspective=g.Perspective(yfov=yfov, aspectRatio=aspect, znear=0.01)))
        node = g.Node(name=name, camera=0)
        if isinstance(m, tuple):  # (translation, rotation, scale)
            node.translation, node.rotation, node.scale = (list(map(float, v)) for v in m)
        else:
            node.matrix = np.asarray(m, float).T.reshape(-1).tolist()
        nodes.append(node)
    used = list(extensions_required)
    extensions = {}
    if lights:
        extensions["KHR_lights_punctual"] = {"lights": [lt for lt, _ in lights]}
        used.append("KHR_lights_punctual")
        for i, (_, m) in enumerate(lights):
            node = g.Node(extensions={"KHR_lights_punctual": {"light": i}})
            if isinstance(m, tuple):  # (translation, rotation, scale)
                node.translation, node.rotation, node.scale = (list(map(float, v)) for v in m)
            else:
                node.matrix = np.asarray(m, float).T.reshape(-1).tolist()
            nodes.append(node)
    gl_images, textures = [], []
    for png in images:
        while len(blob) % 4:
            blob.append(0)
        views.append(g.BufferView(buffer=0, byteOffset=len(blob), byteLength=len(png)))
        blob.extend(png)
        gl_images.append(g.Image(bufferView=len(views) - 1, mimeType="image/png"))
        textures.append(g.Texture(source=len(gl_images) - 1, sampler=0))
    mats = [g.Material(**_material(m)) for m in materials]
    children = set()
    for i, (_, _, _, extras) in enumerate(meshes):
        if "parent" in extras:
            nodes[extras["parent"]].children = [*(nodes[extras["parent"]].children or []), i]
            children.add(i)
    gl_animations = []
    if animations:
        samplers, channels = [], []
        for node, prop, times, values, interp in animations:
            t = add(np.asarray(times, float).reshape(-1), g.SCALAR)
            v = np.asarray(values, float)
            v = add(v.reshape(-1, v.shape[-1]), {3: g.VEC3, 4: g.VEC4}[v.shape[-1]])
            samplers.append(g.AnimationSampler(input=t, output=v, interpolation=interp))
            channels.append(g.AnimationChannel(sampler=len(samplers) - 1, target=g.AnimationChannelTarget(node=node,
                                                                                                         path=prop)))
        gl_animations.append(g.Animation(samplers=samplers, channels=channels))
    roots = [i for i in range(len(nodes)) if i not in children]
    doc = g.GLTF2(scene=0, scenes=[g.Scene(nodes=roots)], nodes=nodes, meshes=gl_meshes, animations=gl_animations,
                  accessors=accessors, bufferViews=views, buffers=[g.Buffer(byteLength=len(blob))], materials=mats,
                  cameras=cameras, extensions=extensions, extensionsUsed=sorted(set(used)),
                  extensionsRequired=list(extensions_required), images=gl_images, textures=textures,
                  samplers=[g.Sampler(magFilter=9728, minFilter=9728)] if images else [])
    doc.set_binary_blob(bytes(blob))
    if str(path).endswith(".glb"):
        doc.save_binary(str(path))
    else:
        doc.convert_buffers(g.BufferFormat.DATAURI)
        doc.save_json(str(path))
    return str(path)


def _material(m: dict) -> dict:
    m = dict(m)
    pbr = m.pop("pbr", {})
    out = {"pbrMetallicRoughness": g.PbrMetallicRoughness(
        baseColorFactor=pbr.get("baseColorFactor", [1, 1, 1, 1]), metallicFactor=pbr.get("metallicFactor", 1.0),
        roughnessFactor=pbr.get("roughnessFactor", 1.0),
        baseColorTexture=g.TextureInfo(**pbr["baseColorTexture"]) if "baseColorTexture" in pbr else None)}
    if "normalTexture" in m:
        out["normalTexture"] = g.NormalMaterialTexture(**m.pop("normalTexture"))
    out.update(m)
    return out


def camera_node(to_world_mitsuba: np.ndarray) -> np.ndarray:
    """The glTF camera node's matrix for a restir (Mitsuba) camera-to-world: glTF's camera looks
    down -Z with +X to the right, Mitsuba's down +Z with +X to the left."""
    return np.asarray(to_world_mitsuba, float) @ np.diag([-1.0, 1.0, -1.0, 1.0])


def yfov_of(fov_x_deg: float, aspect: float) -> float:
    return 2 * math.atan(math.tan(math.radians(fov_x_deg) / 2) / aspect)


def appendix_b(base, metallic, alpha, wi, wo):
    """f cos_o as the glTF 2.0 specification writes it (Appendix B, "complete model")."""
    h = wi + wo
    h /= np.linalg.norm(h, axis=1, keepdims=True)
    vh, nh, nl, nv = (np.sum(wi * h, 1), h[:, 2], wo[:, 2], wi[:, 2])
    f0 = 0.04 * (1 - metallic) + base * metallic
    F = f0[None] + (1 - f0[None]) * ((1 - np.abs(vh)) ** 5)[:, None]
    a2 = alpha * alpha
    D = a2 / (np.pi * (nh * nh * (a2 - 1) + 1) ** 2)
    V = 0.5 / (nl * np.sqrt(nv * nv * (1 - a2) + a2) + nv * np.sqrt(nl * nl * (1 - a2) + a2))
    c_diff = base * (1 - metallic)
    f = (1 - F) * c_diff[None] / np.pi + F * (D * V)[:, None]
    return f * nl[:, None]
