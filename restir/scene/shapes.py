"""Triangle meshes for every supported shape, as un-indexed corner arrays.

A `TriMesh` holds positions (T,3,3), normals (T,3,3) or None (flat shading) and uvs (T,3,2)
in object space. Analytic shapes (disk, sphere) are tessellated with their radius scaled so
the surface area, and so an emitter's power, is exactly that of the analytic shape.
"""
import re
from dataclasses import dataclass

import numpy as np

from .errors import SceneError

SPHERE_SEGMENTS = (128, 64)   # (phi, theta)
DISK_SEGMENTS = 128


@dataclass
class TriMesh:
    positions: np.ndarray
    normals: np.ndarray | None
    uvs: np.ndarray
    emission: np.ndarray | None = None  # (T, 3) per-triangle radiance, replacing the emitter's (glTF's textures)
    tangents: np.ndarray | None = None  # (T, 3, 4) per corner: a normal map's tangent and bitangent sign (glTF)


def barycentric_uvs(num_triangles: int) -> np.ndarray:
    """The uvs of a mesh without texture coordinates, as Mitsuba 3 defines them: each triangle's
    own barycentric parameterization, uv = (b1, b2), so corners (0, 0), (1, 0), (0, 1). A texture
    or bump map on such a mesh then reads what Mitsuba's does, and dp/du = p1 - p0."""
    return np.broadcast_to(np.array([[0.0, 0.0], [1.0, 0.0], [0.0, 1.0]]), (num_triangles, 3, 2)).copy()


def _from_indexed(v, f, n=None, uv=None) -> TriMesh:
    f = np.asarray(f, np.int64)
    pos = np.asarray(v, np.float64)[f]
    nrm = None if n is None else np.asarray(n, np.float64)[f]
    if uv is None:
        uvs = barycentric_uvs(len(f))
    else:
        uvs = np.asarray(uv, np.float64)[f]
    return TriMesh(pos, nrm, uvs)


def rectangle() -> TriMesh:
    v = [[-1, -1, 0], [1, -1, 0], [1, 1, 0], [-1, 1, 0]]
    uv = [[0, 0], [1, 0], [1, 1], [0, 1]]
    f = [[0, 1, 2], [2, 3, 0]]
    return _from_indexed(v, f, [[0, 0, 1]] * 4, uv)


def cube() -> TriMesh:
    verts, norms, uvs, faces = [], [], [], []
    for axis in range(3):
        for sign in (-1.0, 1.0):
            n = np.zeros(3)
            n[axis] = sign
            a, b = [i for i in range(3) if i != axis]
            base = len(verts)
            for (s, t) in [(-1, -1), (1, -1), (1, 1), (-1, 1)]:
                p = np.zeros(3)
                p[axis], p[a], p[b] = sign, s, t
                verts.append(p)
                norms.append(n)
                uvs.append([(s + 1) / 2, (t + 1) / 2])
            quad = [[base, base + 1, base + 2], [base, base + 2, base + 3]]
            # orient each face's winding outward
            p0, p1, p2 = (verts[i] for i in quad[0])
            if np.dot(np.cross(p1 - p0, p2 - p0), n) < 0:
                quad = [[q[0], q[2], q[1]] for q in quad]
            faces += quad
    return _from_indexed(verts, faces, norms, uvs)


def disk(segments: int = DISK_SEGMENTS) -> TriMesh:
    phi = np.linspace(0, 2 * np.pi, segments + 1)[:-1]
    # A regular polygon of circumradius r has area (n/2) r^2 sin(2 pi/n): match pi.
    r = np.sqrt(np.pi / (0.5 * segments * np.sin(2 * np.pi / segments)))
    ring = np.stack([r * np.cos(phi), r * np.sin(phi), np.zeros_like(phi)], 1)
    v = np.vstack([[0, 0, 0], ring])
    f = [[0, 1 + i, 1 + (i + 1) % segments] for i in range(segments)]
    uv = np.vstack([[0, 0], np.stack([np.ones_like(phi), phi / (2 * np.pi)], 1)])
    return _from_indexed(v, f, [[0, 0, 1]] * len(v), uv)


def sphere(segments=SPHERE_SEGMENTS) -> TriMesh:
    n_phi, n_theta = segments
    th = np.linspace(0, np.pi, n_theta + 1)
    ph = np.linspace(0, 2 * np.pi, n_phi + 1)
    T, P = np.meshgrid(th, ph, indexing="ij")
    dirs = np.stack([np.sin(T) * np.cos(P), np.sin(T) * np.sin(P), np.cos(T)], -1).reshape(-1, 3)
    uv = np.stack([P / (2 * np.pi), T / np.pi], -1).reshape(-1, 2)
    idx = lambda i, j: i * (n_phi + 1) + j  # noqa: E731
    f = []
    for i in range(n_theta):
        for j in range(n_phi):
            a, b, c, d = idx(i, j), idx(i + 1, j), idx(i + 1, j + 1), idx(i, j + 1)
            if i > 0:
                f.append([a, b, d])
            if i < n_theta - 1:
                f.append([b, c, d])
    m = _from_indexed(dirs, f, dirs, uv)
    # Outward winding, and area scaled to 4 pi.
    e = np.cross(m.positions[:, 1] - m.positions[:, 0], m.positions[:, 2] - m.positions[:, 0])
    if np.sum(np.einsum("ij,ij->i", e, m.positions.mean(1))) < 0:
        m.positions = m.positions[:, ::-1]
        m.normals = m.normals[:, ::-1]
        m.uvs = m.uvs[:, ::-1]
        e = -e
    area = 0.5 * np.linalg.norm(e, axis=1).sum()
    m.positions *= np.sqrt(4 * np.pi / area)
    return m


def load_obj(path: str, loc: str) -> TriMesh:
    """Wavefront OBJ: v/vt/vn, polygons fan-triangulated, negative (relative) indices.

    As Mitsuba does, texture v is flipped (1 - v) so that images are not upside down. Files in
    the regular form exporters write (every `v` and `vn` with 3 numbers, every `vt` with 2 or 3,
    one corner format per file, positive indices in range) are read with numpy's string conversions
    (`_read_obj_regular`: Bitterli's staircase, 774 files, 262 k triangles, in a tenth of the
    time); anything else, errors included, line by line (`_read_obj_lines`, which names the line).
    Both give the same mesh (tests/unit/test_loader.py).
    """
    try:
        f = open(path, "r", errors="replace")
    except OSError as e:
        raise SceneError(f"cannot open mesh '{path}': {e.strerror}", loc) from None
    with f:
        text = f.read()
    arrays = _read_obj_regular(text)
    if arrays is None:
        arrays = _read_obj_lines(text, path)
    v, vt, vn, fv, ft, fn = arrays
    if not len(fv):
        raise SceneError(f"mesh '{path}' has no faces", loc)
    for array, what in ((v, "v"), (vt, "vt"), (vn, "vn")):
        check_finite_vertices(path, loc, array, what)
    pos = v[fv]
    nrm = vn[fn] if len(vn) and (fn >= 0).all() else None
    uvs = vt[ft] if len(vt) and (ft >= 0).all() else barycentric_uvs(len(fv))
    if nrm is None:
        nrm = smooth_normals(v, fv)
    return TriMesh(pos, nrm, uvs)


def _numbers(lines: list, width: int) -> np.ndarray | None:
    """The numbers after the keyword of lines that each hold exactly `width` of them, or None."""
    if not lines:
        return np.zeros((0, width))
    toks = " ".join(lines).split()
    if len(toks) != (width + 1) * len(lines):
        return None
    del toks[:: width + 1]  # the keywords
    return np.array(list(map(float, toks)), np.float64).reshape(len(lines), width)


def _read_obj_regular(text: str):
    """(v, vt, vn, fv, ft, fn) of an OBJ in the regular form (see load_obj), or None."""
    vl, tl, nl, fl = [], [], [], []
    for line in text.splitlines():
        key = line[:3]
        if key[:2] == "v ":
            vl.append(line)
        elif key == "vt ":
            tl.append(line)
        elif key == "vn ":
            nl.append(line)
        elif key[:2] == "f ":
            fl.append(line)
        elif line.strip() and line.lstrip()[0] != "#" and line.split()[0] in ("v", "vt", "vn", "f"):
            return None  # indented or tab-separated records: the line reader
    try:
        v, vn = _numbers(vl, 3), _numbers(nl, 3)
        vt = _numbers(tl, 2)
        if vt is None:
            vt = _numbers(tl, 3)
            vt = None if vt is None else vt[:, :2]
        if v is None or vn is None or vt is None:
            return None
        vt[:, 1] = 1.0 - vt[:, 1]
        faces = [line.split() for line in fl]
        counts = np.fromiter((len(t) - 1 for t in faces), np.int64, len(faces))
        if len(faces) and counts.min() < 3:
            return None
        # every corner as v, v/t, v/t/n or v//n, one format for the file: one split for all of them
        corners = " ".join(" ".join(t[1:]) for t in faces)
        n_corners = int(counts.sum())
        first_corner = faces[0][1] if faces else "1"
        width = first_corner.count("/") + 1
        no_uv = "//" in first_corner
        corner = r"\d+//\d+" if no_uv else r"\d+" + r"/\d+" * (width - 1)
        if width > 3 or (faces and re.fullmatch(f"{corner}( {corner})*", corners) is None):
            return None  # corner formats mixed in one file, or a negative index
        toks = corners.replace("//", "/").replace("/", " ").split()
        cols = width - 1 if no_uv else width
        if len(toks) != n_corners * cols:
            return None  # corner formats mixed in one file
        table = np.array(list(map(int, toks)), np.int64).reshape(n_corners, cols)
        if (table <= 0).any():
            return None  # 0 is invalid; a negative index counts back from its own line
        table = table - 1
        if no_uv:
            table = np.stack([table[:, 0], np.full(n_corners, -1), table[:, 1]], 1)
        idx = []
        for k, count in enumerate((len(v), len(vt), len(vn))):
            if k >= table.shape[1]:
                idx.append(np.full(n_corners, -1, np.int64))
                continue
            i = table[:, k]
            if (i >= count).any():
                return None  # the line reader names the index out of range
            idx.append(i)
    except (ValueError, IndexError):
        return None
    # fan triangulation: polygon p with n corners gives (c0, ck, ck+1), k = 1 .. n - 2
    tris = counts - 2
    first = np.cumsum(counts) - counts
    face = np.repeat(np.arange(len(counts)), tris)
    k = np.arange(int(tris.sum())) - np.repeat(np.cumsum(tris) - tris, tris) + 1
    corners = np.stack([first[face], first[face] + k, first[face] + k + 1], 1)
    return v, vt, vn, idx[0][corners], idx[1][corners], idx[2][corners]


def _read_obj_lines(text: str, path: str):
    """(v, vt, vn, fv, ft, fn) of any OBJ load_obj reads, line by line; errors name the line."""
    v, vt, vn = [], [], []
    fv, ft, fn = [], [], []
    for lineno, line in enumerate(text.splitlines(), 1):
        parts = line.split()
        if not parts:
            continue
        key = parts[0]
        try:
            if key in ("v", "vn") and len(parts) < 4:
                raise SceneError(f"'{key}' needs 3 numbers: {line.strip()}", f"{path}:{lineno}")
            if key == "v":
                v.append([float(x) for x in parts[1:4]])
            elif key == "vt":
                vt.append([float(parts[1]), 1.0 - float(parts[2]) if len(parts) > 2 else 0.0])
            elif key == "vn":
                vn.append([float(x) for x in parts[1:4]])
            elif key == "f":
                corners = []
                for c in parts[1:]:
                    ids = c.split("/")
                    trip = []
                    for k, count in enumerate((len(v), len(vt), len(vn))):
                        if k < len(ids) and ids[k]:
                            i = int(ids[k])
                            i = i - 1 if i > 0 else count + i
                            if not 0 <= i < count:
                                raise SceneError(f"index {ids[k]} out of range", f"{path}:{lineno}")
                            trip.append(i)
                        else:
                            trip.append(-1)
                    corners.append(trip)
                for k in range(1, len(corners) - 1):
                    tri = [corners[0], corners[k], corners[k + 1]]
                    fv.append([c[0] for c in tri])
                    ft.append([c[1] for c in tri])
                    fn.append([c[2] for c in tri])
        except (ValueError, IndexError):
            raise SceneError(f"cannot parse OBJ line: {line.strip()}", f"{path}:{lineno}") from None
    floats = [np.asarray(a, np.float64).reshape(-1, w) for a, w in ((v, 3), (vt, 2), (vn, 3))]
    return (*floats, *[np.asarray(x, np.int64).reshape(-1, 3) for x in (fv, ft, fn)])


def load_ply(path: str, loc: str, smooth_missing_normals: bool = True) -> TriMesh:
    from plyfile import PlyData, PlyElementParseError

    try:
        try:
            # A binary file of triangles is read as one array (400x faster than face by face);
            # plyfile checks every face's count and raises on the first that is not 3.
            ply = PlyData.read(path, known_list_len={"face": {"vertex_indices": 3, "vertex_index": 3}})
        except PlyElementParseError:
            ply = PlyData.read(path)
    except OSError as e:
        raise SceneError(f"cannot open mesh '{path}': {e.strerror}", loc) from None
    except Exception as e:  # plyfile raises several exception types for bad files
        raise SceneError(f"cannot parse PLY '{path}': {e}", loc) from None
    elements = {e.name for e in ply.elements}
    if "vertex" not in elements or "face" not in elements:
        raise SceneError(f"PLY '{path}' has no {'vertex' if 'vertex' not in elements else 'face'} element", loc)
    vert = ply["vertex"]
    names = vert.data.dtype.names
    if not {"x", "y", "z"} <= set(names) or not ply["face"].data.dtype.names:
        raise SceneError(f"PLY '{path}': the vertices need x, y and z, and the faces a list of vertex indices",
                         loc)
    v = np.stack([vert["x"], vert["y"], vert["z"]], 1).astype(np.float64)
    check_finite_vertices(path, loc, v, "vertex")
    lists = ply["face"].data[ply["face"].data.dtype.names[0]]
    if lists.dtype != object:  # the triangles' array (the known-length read)
        f = np.array(lists, np.int64).reshape(-1, 3)
    else:  # polygons of any size (or an ASCII file): fans
        faces = []
        for face in lists:
            for k in range(1, len(face) - 1):
                faces.append([face[0], face[k], face[k + 1]])
        f = np.array(faces, np.int64).reshape(-1, 3)
    if len(f) == 0:
        raise SceneError(f"mesh '{path}' has no faces", loc)
    if f.min() < 0 or f.max() >= len(v):
        bad = int(f[(f < 0) | (f >= len(v))][0])
        raise SceneError(f"PLY '{path}': a face refers to vertex {bad}, but there are {len(v)} vertices", loc)
    n = np.stack([vert["nx"], vert["ny"], vert["nz"]], 1) if "nx" in names else None
    uv = None
    for a, b in (("u", "v"), ("s", "t"), ("texture_u", "texture_v")):
        if a in names:
            uv = np.stack([vert[a], vert[b]], 1)
    for array, what in ((n, "normal"), (uv, "texture coordinate")):
        if array is not None:
            check_finite_vertices(path, loc, np.asarray(array, np.float64), what)
    mesh = _from_indexed(v, f, n, uv)
    if mesh.normals is None and smooth_missing_normals:  # Mitsuba's PLY: smooth; pbrt-v4's: flat
        mesh.normals = smooth_normals(v, f)
    return mesh


def check_finite_vertices(path: str, loc: str, v: np.ndarray, what: str) -> None:
    """Refuse a mesh with a non-finite vertex (a triangle through it would vanish from the image
    without a word)."""
    bad = ~np.isfinite(v).all(axis=1)
    if bad.any():
        raise SceneError(f"mesh '{path}': {what} {int(np.argmax(bad)) + 1} of {len(v)} has a non-finite "
                         f"coordinate {v[np.argmax(bad)].tolist()}", loc)


def smooth_normals(v: np.ndarray, f: np.ndarray) -> np.ndarray:
    """Angle-weighted vertex normals (for meshes that come without any)."""
    p = v[f]
    acc = np.zeros_like(v)
    fn = np.cross(p[:, 1] - p[:, 0], p[:, 2] - p[:, 0])
    fn /= np.maximum(np.linalg.norm(fn, axis=1, keepdims=True), 1e-30)
    for c in range(3):
        e1 = p[:, (c + 1) % 3] - p[:, c]
        e2 = p[:, (c + 2) % 3] - p[:, c]
        cosang = np.einsum("ij,ij->i", e1, e2) / np.maximum(np.linalg.norm(e1, axis=1) * np.linalg.norm(e2, axis=1), 1e-30)
        ang = np.arccos(np.clip(cosang, -1, 1))
        np.add.at(acc, f[:, c], fn * ang[:, None])
    acc /= np.maximum(np.linalg.norm(acc, axis=1, keepdims=True), 1e-30)
    return acc[f]
