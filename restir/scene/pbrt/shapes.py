"""pbrt-v4's shapes as world-space triangles, oriented as pbrt-v4 orients them.

pbrt-v4's geometric normal of a triangle is the cross product of its edges in world space,
turned toward the vertex normals when the mesh has them, else flipped when ReverseOrientation
and a mirroring transform disagree; a sphere's or a disk's faces outward (+z for a disk) unless
ReverseOrientation. restir takes a triangle's normal from its winding, so triangles are rewound
to match (a one-sided emitter then emits to the same side).

Texture coordinates: pbrt-v4 looks images up at (u, 1 - v) with the first row at the top; restir
(as Mitsuba 3) at (u, v). Every mesh's v is stored as 1 - v, and materials.py's uv mappings
account for it, so a texture lands where pbrt-v4 puts it.
"""
import os

import numpy as np

from .. import shapes as shape_lib
from ..errors import SceneError, warn
from ..transforms import transform_normals, transform_points
from .params import ParamSet

SUPPORTED = ("trianglemesh", "plymesh", "sphere", "disk", "bilinearmesh")
NOT_SUPPORTED = ("cylinder", "curve", "loopsubdiv", "cone", "paraboloid", "hyperboloid", "nurbs")


def read_shape(kind: str, ps: ParamSet, base_dir: str):
    """Check the shape's parameters now (errors before any work) and return a function of
    (world transform, reverse orientation) that builds its TriMesh, and its area in object space
    when cheap (None for a PLY file)."""
    if kind in NOT_SUPPORTED:
        raise SceneError(f"Shape '{kind}' is not supported (supported: {', '.join(SUPPORTED)})", ps.loc)
    if kind not in SUPPORTED:
        raise SceneError(f"unknown Shape '{kind}' (supported: {', '.join(SUPPORTED)})", ps.loc)
    if kind == "trianglemesh":
        v, f, n, uv = _inline_mesh(ps, 3)
        return (lambda m, rev: _oriented(v, f, n, uv, m, rev)), None
    if kind == "bilinearmesh":
        v, q, n, uv = _inline_mesh(ps, 4)
        if uv is None:
            uv = np.zeros((len(v), 2))
            uv[q[:, 1], 0] = 1.0
            uv[q[:, 2], 1] = 1.0
            uv[q[:, 3]] = 1.0
        # p00 p10 p01 p11: two triangles (p00, p10, p11) and (p00, p11, p01)
        f = np.concatenate([q[:, [0, 1, 3]], q[:, [0, 3, 2]]])
        a, b, c, d = (v[q[:, i]] for i in range(4))
        bent = np.abs(np.einsum("ij,ij->i", np.cross(b - a, c - a), d - a))
        scale = np.maximum(np.linalg.norm(b - a, axis=1) * np.linalg.norm(c - a, axis=1), 1e-30)
        if np.any(bent > 1e-4 * scale ** 1.5):
            warn("bilinearmesh: a patch is not planar; it is rendered as two triangles (pbrt-v4 renders the curved "
                 "bilinear surface)", ps.loc)
        return (lambda m, rev: _oriented(v, f, n, uv, m, rev)), None
    if kind == "plymesh":
        fname = ps.string("filename")
        if fname is None:
            raise SceneError("plymesh needs 'string filename'", ps.loc)
        for p in ("displacement", "edgelength"):
            if ps.has(p):
                raise SceneError(f"plymesh: '{p}' (displacement subdivision) is not supported", ps.loc_of(p))
        path = fname if os.path.isabs(fname) else os.path.join(base_dir, fname)
        if not os.path.exists(path):
            raise SceneError(f"mesh file '{fname}' not found", ps.loc_of("filename"))
        if fname.lower().endswith(".gz"):
            raise SceneError("gzip-compressed PLY files are not supported: decompress it first", ps.loc_of("filename"))
        loc = ps.loc_of("filename")

        def load_ply(m, rev):
            mesh = shape_lib.load_ply(path, loc, smooth_missing_normals=False)
            return _oriented_soup(mesh, m, rev, analytic=False)

        return load_ply, None
    if kind == "sphere":
        r = ps.float("radius", 1.0)
        if r <= 0:
            raise SceneError("sphere: radius must be positive", ps.loc_of("radius"))
        for p, full in (("zmin", -r), ("zmax", r), ("phimax", 360.0)):
            if ps.has(p) and ps.float(p) != full:
                raise SceneError(f"sphere: a partial sphere ('{p}') is not supported", ps.loc_of(p))
        mesh = shape_lib.sphere()
        mesh.positions = mesh.positions * r
        # pbrt-v4: u = phi / 2 pi, v = (theta - pi) / (0 - pi) = 1 - theta / pi; restir's sphere
        # has (phi / 2 pi, theta / pi), which is pbrt-v4's with v flipped, as stored here
        return (lambda m, rev: _oriented_soup(shape_lib.TriMesh(mesh.positions, mesh.normals, mesh.uvs.copy()), m,
                                              rev, analytic=True, flip_v=False)), 4.0 * np.pi * r * r
    # disk
    r = ps.float("radius", 1.0)
    h = ps.float("height", 0.0)
    if r <= 0:
        raise SceneError("disk: radius must be positive", ps.loc_of("radius"))
    for p, full in (("innerradius", 0.0), ("phimax", 360.0)):
        if ps.has(p) and ps.float(p) != full:
            raise SceneError(f"disk: '{p}' (an annulus or a sector) is not supported", ps.loc_of(p))
    mesh = shape_lib.disk()
    pos = mesh.positions * np.array([r, r, 1.0]) + np.array([0.0, 0.0, h])
    radial = np.linalg.norm(mesh.positions[..., :2], axis=-1) / np.max(np.linalg.norm(mesh.positions[..., :2], axis=-1))
    phi = np.mod(np.arctan2(mesh.positions[..., 1], mesh.positions[..., 0]), 2 * np.pi) / (2 * np.pi)
    uvs = np.stack([phi, 1.0 - radial], -1)  # pbrt-v4: u = phi / phimax, v = (rmax - r) / rmax
    return (lambda m, rev: _oriented_soup(shape_lib.TriMesh(pos, mesh.normals, uvs), m, rev, analytic=True)), \
        np.pi * r * r


def _inline_mesh(ps: ParamSet, corners: int):
    what = "trianglemesh" if corners == 3 else "bilinearmesh"
    p = ps.array("P", ("point3", "point"), 3)
    if p is None:
        raise SceneError(f"{what} needs 'point3 P'", ps.loc)
    idx = ps.ints("indices")
    if idx is None:
        if len(p) != corners:
            raise SceneError(f"{what} needs 'integer indices' (only a single {'triangle' if corners == 3 else 'patch'} "
                             "may leave them out)", ps.loc)
        idx = np.arange(corners)
    if len(idx) % corners or len(idx) == 0:
        raise SceneError(f"{what}: 'indices' holds {len(idx)} numbers, not a positive multiple of {corners}",
                         ps.loc_of("indices"))
    if idx.min() < 0 or idx.max() >= len(p):
        raise SceneError(f"{what}: an index refers to vertex {int(idx[(idx < 0) | (idx >= len(p))][0])}, but there are "
                         f"{len(p)} vertices", ps.loc_of("indices"))
    n = ps.array("N", ("normal", "normal3"), 3)
    uv = ps.array("uv", ("point2", "float"), 2)
    if uv is None and ps.has("st"):
        uv = ps.array("st", ("point2", "float"), 2)
    for name, arr in (("N", n), ("uv", uv)):
        if arr is not None and len(arr) != len(p):
            raise SceneError(f"{what}: '{name}' has {len(arr)} entries for {len(p)} vertices", ps.loc_of(name))
    if ps.has("S"):
        ps.array("S", ("vector3", "vector"), 3)
        warn(f"{what}: the tangents 'S' are not used (restir's shading frame comes from the normals and uvs)",
             ps.loc_of("S"))
    ps.ignore("faceIndices")
    return p, idx.reshape(-1, corners), n, uv


def _oriented(v, f, n, uv, m, rev) -> shape_lib.TriMesh:
    if uv is None:  # pbrt-v4's default uvs of a triangle
        uvs = np.broadcast_to(np.array([[0.0, 0.0], [1.0, 0.0], [1.0, 1.0]]), (len(f), 3, 2)).copy()
    else:
        uvs = np.asarray(uv, np.float64)[f]
    mesh = shape_lib.TriMesh(np.asarray(v, np.float64)[f], None if n is None else np.asarray(n, np.float64)[f], uvs)
    return _oriented_soup(mesh, m, rev, analytic=False)


def _oriented_soup(mesh: shape_lib.TriMesh, m: np.ndarray, rev: bool, analytic: bool,
                   flip_v: bool = True) -> shape_lib.TriMesh:
    pos = transform_points(m, mesh.positions.reshape(-1, 3)).reshape(-1, 3, 3)
    nrm = None if mesh.normals is None else transform_normals(m, mesh.normals.reshape(-1, 3)).reshape(-1, 3, 3)
    uvs = mesh.uvs.copy()
    if flip_v:
        uvs[..., 1] = 1.0 - uvs[..., 1]
    swaps = np.linalg.det(m[:3, :3]) < 0
    face = np.cross(pos[:, 1] - pos[:, 0], pos[:, 2] - pos[:, 0])
    if analytic:
        # outward in object space; a mirror turns the winding inward, ReverseOrientation turns both
        flip = np.full(len(pos), bool(swaps) != bool(rev))
        if rev and nrm is not None:
            nrm = -nrm
    elif nrm is not None:
        flip = np.einsum("ij,ij->i", face, nrm.sum(axis=1)) < 0
    else:
        flip = np.full(len(pos), bool(swaps) != bool(rev))
    if np.any(flip):
        pos[flip] = pos[flip][:, ::-1]
        uvs[flip] = uvs[flip][:, ::-1]
        if nrm is not None:
            nrm[flip] = nrm[flip][:, ::-1]
    return shape_lib.TriMesh(pos, nrm, uvs)
