"""Lighter meshes for drawing the OGBench arm (levels of detail), cached on disk.

The UR5e arm and Robotiq gripper carry ~185k mesh faces; a 64x64 frame shows the arm on a few
hundred pixels, and on a CPU (EGL software rendering, 4x multisampling) drawing them is most of
a frame's cost, about proportional to the number of faces.
:func:`render_mesh_model` compiles the same MJCF with every mesh of at least :data:`MIN_FACES`
faces decimated to ``ratio`` of its faces: its vertices are first clustered on a
:data:`CLUSTER_CELL` grid (2 mm, below a pixel of a 224-px frame; each cell becomes the mean of
its vertices), then ``fast-simplification`` (quadric edge collapse) removes faces down to the
target. Quadric collapse alone stalls on some of these CAD meshes (at ratio 0.1 the gripper
mount kept 54 % of its faces, an upper-arm part 89 %) and the decimated parts looked faceted;
after the clustering every mesh reaches the target, and the picture is closer to the exact one
(Cube, ``bench/bench_mujoco.py --picture``: MAD at 64x64 against ``"high"`` 0.67 instead of
1.04, with the coarser floor below, at half the faces: 20.7k instead of 40.6k). The result only
feeds the GL context (``MjRenderer(..., mesh_model=...)``): physics, collisions and the scene
(poses, colours, lights) keep the exact model, so decimation changes pixels only.

Which ``render_quality`` decimates (:data:`MESH_DETAIL`): ``"low"`` and ``"medium"``; ``"high"``
keeps the exact meshes (upstream's picture, bit for bit).

The floor has a level of detail too (:data:`PLANE_GRID`): MuJoCo draws a plane as a grid of quads
whose spacing is the plane's third size (OGBench's floor: 1 cm, 102 x 102 quads, ~20k triangles,
half the decimated arm), only so that per-vertex lighting varies smoothly across it. The render
model draws it with a coarser grid; textures, colours and shadows on it are unchanged.

Each decimated mesh is stored under ``<cache>/meshes/<sha256>.npz`` (``get_cache_dir``), the
hash taken over the source vertices, faces, the ratio and :data:`ALGORITHM`, so a mesh is
decimated once per machine; compiled render models are kept per process.
"""

from __future__ import annotations

import hashlib
import logging
import os
from typing import Any

import numpy as np

from ...errors import ConfigError

logger = logging.getLogger(__name__)

#: render_quality -> fraction of faces kept in the large meshes (None: exact meshes)
MESH_DETAIL: dict[str, float | None] = {"low": 0.05, "medium": 0.1, "high": None}
#: render_quality -> grid spacing (m) of the planes in the render model (None: the model's own)
PLANE_GRID: dict[str, float | None] = {"low": 0.05, "medium": 0.03, "high": None}
MIN_FACES = 1000  # smaller meshes are drawn as they are
ALGORITHM = "cluster-2mm+fast-simplification-qem-v2"  # part of the cache key: bump when the recipe changes
CLUSTER_CELL = 0.002  # m: vertices in one cell of this grid become one vertex before the quadric collapse
_WARNED: list[bool] = []


def check_ratio(ratio: Any) -> float:
    """``ratio`` as a float in (0, 1]; ConfigError otherwise."""
    try:
        value = float(ratio)
    except (TypeError, ValueError):
        value = float("nan")
    if isinstance(ratio, bool) or not 0.0 < value <= 1.0:
        raise ConfigError(f"mesh decimation requires a ratio in (0, 1] (fraction of faces kept), got {ratio!r}")
    return value


def decimate(vertices: np.ndarray, faces: np.ndarray, ratio: float, cache_dir=None) -> tuple[np.ndarray, np.ndarray]:
    """``(vertices (V, 3) float64, faces (F, 3) int32)`` of the mesh with about ``ratio`` of its faces.

    Read from ``<cache>/meshes/`` when this mesh and ratio were decimated before (``cache_dir``:
    as :func:`~stable_worldmodel.data.utils.get_cache_dir`), else computed and stored there.
    """
    ratio = check_ratio(ratio)
    vertices = np.ascontiguousarray(vertices, np.float64)
    faces = np.ascontiguousarray(faces, np.int32)
    if vertices.ndim != 2 or vertices.shape[1] != 3 or faces.ndim != 2 or faces.shape[1] != 3:
        raise ConfigError(
            f"mesh decimation requires vertices (V, 3) and faces (F, 3), got {vertices.shape} and {faces.shape}"
        )
    from ...data.utils import get_cache_dir

    digest = hashlib.sha256()
    for part in (ALGORITHM.encode(), np.float64(ratio).tobytes(), vertices.tobytes(), faces.tobytes()):
        digest.update(part)
    path = get_cache_dir(cache_dir, "meshes") / f"{digest.hexdigest()}.npz"
    if path.exists():
        with np.load(path) as cached:
            return cached["vertices"], cached["faces"]
    out_v, out_f = _simplify(vertices, faces, ratio)
    tmp = path.with_name(f"{path.stem}.{os.getpid()}.tmp.npz")
    np.savez(tmp, vertices=out_v, faces=out_f)
    os.replace(tmp, path)  # atomic: parallel workers never read a half-written file
    return out_v, out_f


def _simplify(vertices: np.ndarray, faces: np.ndarray, ratio: float) -> tuple[np.ndarray, np.ndarray]:
    import fast_simplification

    _, inverse = np.unique(np.round(vertices / CLUSTER_CELL), axis=0, return_inverse=True)
    inverse = inverse.reshape(-1)
    counts = np.bincount(inverse)
    welded = np.zeros((len(counts), 3))
    np.add.at(welded, inverse, vertices)
    welded /= counts[:, None]  # each cell: the mean of its vertices
    tris = inverse[faces]
    tris = tris[(tris[:, 0] != tris[:, 1]) & (tris[:, 1] != tris[:, 2]) & (tris[:, 0] != tris[:, 2])]
    if len(tris) < 4:  # a mesh about the size of a cell: nothing sensible to decimate
        return vertices, faces
    target = max(1, round(ratio * len(faces)))  # ratio of the source faces; the clustering took some already
    reduction = max(0.0, 1.0 - target / max(1, len(tris)))
    out_v, out_f = fast_simplification.simplify(welded, tris.astype(np.int32), target_reduction=reduction)
    return np.asarray(out_v, np.float64), np.asarray(out_f, np.int32)


def available() -> bool:
    """True when ``fast-simplification`` is installed; otherwise logs once that meshes stay exact."""
    from ..._optional import is_available

    if is_available("fast_simplification"):
        return True
    if not _WARNED:
        _WARNED.append(True)
        logger.warning(
            "fast-simplification is not installed, so the OGBench arm is drawn with its exact meshes (slower); "
            'install it with: pip install "stable-worldmodel[mujoco]"'
        )
    return False


def render_mesh_model(
    model, xml: str, assets: dict[str, bytes], ratio: float, cache_dir=None, plane_grid: float | None = None
):
    """``model``'s description (``xml``, ``assets``) compiled with decimated large meshes.

    Each mesh of ``model`` with at least :data:`MIN_FACES` faces is decimated in ``model``'s own
    mesh frame (vertices as compiled), and the compiled copy is moved back into that frame
    (MuJoCo re-centres every mesh on its centroid and principal axes), so ``model``'s geom poses
    place it exactly. ``plane_grid`` (m, optional): planes are drawn with at least this grid
    spacing (:data:`PLANE_GRID`). For ``MjRenderer(model, ..., mesh_model=render_mesh_model(...))`` only.
    """
    import mujoco

    ratio = check_ratio(ratio)
    if plane_grid is not None and (
        isinstance(plane_grid, bool) or not isinstance(plane_grid, (int, float)) or not plane_grid > 0
    ):
        raise ConfigError(f"render_mesh_model requires plane_grid > 0 (metres) or None, got {plane_grid!r}")
    spec = mujoco.MjSpec.from_string(xml, assets=assets)
    lighter = []
    for i in range(model.nmesh):
        nface = int(model.mesh_facenum[i])
        if nface < MIN_FACES:
            continue
        mesh = spec.mesh(model.mesh(i).name)
        v0, f0 = int(model.mesh_vertadr[i]), int(model.mesh_faceadr[i])
        verts, faces = decimate(
            model.mesh_vert[v0 : v0 + model.mesh_vertnum[i]], model.mesh_face[f0 : f0 + nface], ratio, cache_dir
        )
        mesh.file, mesh.scale = "", [1.0, 1.0, 1.0]
        mesh.refpos, mesh.refquat = [0.0, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]
        mesh.uservert, mesh.userface = verts.reshape(-1).tolist(), faces.reshape(-1).tolist()
        lighter.append(i)
    out = spec.compile()
    for i in lighter:  # compiled vertex v was user vertex R v + p: back to model's frame
        rot = np.empty(9)
        mujoco.mju_quat2Mat(rot, out.mesh_quat[i])
        rot = rot.reshape(3, 3)
        v0, n0 = int(out.mesh_vertadr[i]), int(out.mesh_normaladr[i])
        verts = out.mesh_vert[v0 : v0 + out.mesh_vertnum[i]]
        verts[:] = verts @ rot.T + out.mesh_pos[i]
        normals = out.mesh_normal[n0 : n0 + out.mesh_normalnum[i]]
        normals[:] = normals @ rot.T
        out.mesh_pos[i], out.mesh_quat[i] = model.mesh_pos[i], model.mesh_quat[i]
    if plane_grid is not None:  # only the tessellation of the drawn plane: the scene keeps model's sizes
        planes = out.geom_type == mujoco.mjtGeom.mjGEOM_PLANE
        out.geom_size[planes, 2] = np.maximum(out.geom_size[planes, 2], float(plane_grid))
    logger.debug("render model: %d meshes decimated to %.3g of their faces", len(lighter), ratio)
    return out
