"""Factors of variation of the OGBench envs: the space, the cube layout rules, and applying the
visual factors and cube sizes to a compiled ``mujoco.MjModel`` (no recompilation).

Space (nested :class:`~stable_worldmodel.spaces.Dict`, N cubes; names, bounds and defaults as
upstream 0.1.1, except the defaults of the start / goal positions: see :mod:`.cube_env`)::

    agent.color              (3,)    gripper colour (robotiq "black" and "pad_gray" materials)
    agent.ee_start_position  (3,)    end-effector start (and goal-scene) position
    camera.angle_delta       (1, 2)  degrees: yaw about world z, then pitch about world x, of the
                                     ``front_pixels`` camera (the one ``render()`` uses)
    cube.color               (N, 3)  cube colours (a cube on its target turns 80 % whiter)
    cube.size                (N,)    half-extent of each cube (m)
    cube.start_position      (N, 2)  start xy of each cube (z: on the floor, or stacked)
    cube.start_yaw           (N,)
    cube.goal_position       (N, 2)  goal xy of each cube
    cube.goal_yaw            (N,)
    floor.color              (2, 3)  the two colours of the floor checker
    light.intensity          (1,)    diffuse intensity of the directional light
    lock_color               (2, 3)  Scene only: colour of a locked drawer / window (handle and button)

Layout rules (``constrain_fn`` of ``cube.size`` / ``cube.start_position`` / ``cube.goal_position``,
so resampling any one of them keeps the layout valid): two cubes are either apart
(``sqrt(2) * (s_i + s_j) + 1 cm`` between centres, so no rotation makes them touch) or stacked
(same xy to 5 mm); each cube's goal is at least :data:`MIN_TRAVEL` from its start; a goal is apart
from every other cube's start. Positions are drawn one cube at a time (:class:`PointsBox`).
"""

from __future__ import annotations

from collections.abc import Callable
from functools import partial

import numpy as np

from ... import spaces

MIN_TRAVEL = 0.08  # m between a cube's start and goal (twice OGBench's success distance)
LAYOUT_MARGIN = 0.01
STACK_TOL = 0.005
SUCCESS_TINT = 0.8  # a cube on its target is drawn this much closer to white (OGBench's light colours)
AGENT_MATERIALS = ("ur5e/robotiq/black", "ur5e/robotiq/pad_gray")
LIGHT = "global"
FLOOR_TEXTURE = "grid"
FLOOR_COLORS = ((0.08, 0.11, 0.16), (0.15, 0.18, 0.25))  # rgb1 / rgb2 of OGBench's floor checker
AGENT_COLOR = (0.61, 0.28, 0.82)  # OGBench's purple
EE_START = (0.425, 0.0, 0.275)
RENDER_CAMERA = "front_pixels"


def box(low, high, init, constrain_fn: Callable | None = None) -> spaces.Box:
    """A float64 factor of ``init``'s shape with bounds broadcast to it."""
    init = np.asarray(init, np.float64)
    low = np.broadcast_to(np.asarray(low, np.float64), init.shape).copy()
    high = np.broadcast_to(np.asarray(high, np.float64), init.shape).copy()
    return spaces.Box(low, high, shape=init.shape, dtype=np.float64, init_value=init, constrain_fn=constrain_fn)


class PointsBox(spaces.Box):
    """An ``(N, 2)`` factor of planar points drawn one at a time: point ``i`` is redrawn until
    ``point_ok(i, p, drawn)`` holds (``drawn``: the points before it), so crowded layouts are
    found without rejecting whole draws. The same rule is its ``constrain_fn``."""

    def __init__(self, low, high, init, point_ok: Callable[[int, np.ndarray, np.ndarray], bool]):
        init = np.asarray(init, np.float64)
        self.point_ok = point_ok
        super().__init__(
            np.broadcast_to(np.asarray(low, np.float64), init.shape).copy(),
            np.broadcast_to(np.asarray(high, np.float64), init.shape).copy(),
            shape=init.shape,
            dtype=np.float64,
            init_value=init,
            constrain_fn=self._all_ok,
        )

    def _all_ok(self, points) -> bool:
        points = np.asarray(points, np.float64)
        return all(self.point_ok(i, points[i], points[:i]) for i in range(len(points)))

    def _draw(self, *args, **kwargs) -> np.ndarray:
        points = np.empty(self.shape)
        for _ in range(50):  # restarts
            for i in range(self.shape[0]):
                for _ in range(200):
                    p = self.np_random.uniform(self.low[i], self.high[i])
                    if self.point_ok(i, p, points[:i]):
                        break
                else:
                    break
                points[i] = p
            else:
                return points
        return points  # constrain_fn rejects it; the space raises after its own tries


class CubeLayout:
    """The layout rules over the live values of the ``cube`` space it is bound to (module
    docstring). It holds that space only, so the variation space pickles without the env."""

    space: spaces.Dict | None = None

    def _value(self, name: str) -> np.ndarray:
        return np.asarray(self.space[name].value, np.float64)

    def point_ok(self, kind: str, i: int, p: np.ndarray, drawn: np.ndarray, sizes=None) -> bool:
        """Point ``i`` of ``kind`` ("start" / "goal") at ``p`` given the points ``drawn`` before it."""
        sizes = self._value("size") if sizes is None else np.asarray(sizes, np.float64)
        other = self._value("goal_position" if kind == "start" else "start_position")
        p = np.asarray(p, np.float64)

        def apart(q, j) -> bool:
            return float(np.hypot(*(p - q))) >= np.sqrt(2.0) * (sizes[i] + sizes[j]) + LAYOUT_MARGIN

        for j, q in enumerate(drawn):  # same kind: apart or stacked
            if not apart(q, j) and float(np.hypot(*(p - q))) > STACK_TOL:
                return False
        for j, q in enumerate(other):  # own start/goal: far enough; other cubes': apart
            if (j == i and float(np.hypot(*(p - q))) < MIN_TRAVEL) or (j != i and not apart(q, j)):
                return False
        return True

    def sizes_ok(self, sizes) -> bool:
        for kind, name in (("start", "start_position"), ("goal", "goal_position")):
            pts = self._value(name)
            if not all(self.point_ok(kind, i, pts[i], pts[:i], sizes) for i in range(len(pts))):
                return False
        return True


def cube_space(n: int, colors: np.ndarray, lo_xy, hi_xy, start_init, goal_init) -> spaces.Dict:
    """The ``cube`` sub-space for ``n`` cubes inside ``[lo_xy, hi_xy]``."""
    layout = CubeLayout()
    layout.space = spaces.Dict(
        {
            "color": box(0.0, 1.0, colors[:n, :3]),
            "goal_position": PointsBox(lo_xy, hi_xy, goal_init, partial(layout.point_ok, "goal")),
            "goal_yaw": box(0.0, 2 * np.pi, np.zeros(n)),
            "size": box(0.01, 0.03, np.full(n, 0.02), constrain_fn=layout.sizes_ok),
            "start_position": PointsBox(lo_xy, hi_xy, start_init, partial(layout.point_ok, "start")),
            "start_yaw": box(0.0, 2 * np.pi, np.zeros(n)),
        },
        sampling_order=["color", "size", "start_position", "start_yaw", "goal_position", "goal_yaw"],
    )
    return layout.space


def common_space(
    cube: spaces.Dict, arm_bounds: np.ndarray, camera_limit: float, light: float, extra: dict | None = None
) -> spaces.Dict:
    """agent / camera / cube / floor / light (+ ``extra`` top-level factors), in alphabetical order as upstream."""
    entries = {
        "agent": spaces.Dict(
            {"color": box(0.0, 1.0, AGENT_COLOR), "ee_start_position": box(arm_bounds[0], arm_bounds[1], EE_START)}
        ),
        "camera": spaces.Dict({"angle_delta": box(-camera_limit, camera_limit, np.zeros((1, 2)))}),
        "cube": cube,
        "floor": spaces.Dict({"color": box(0.0, 1.0, FLOOR_COLORS)}),
        "light": spaces.Dict({"intensity": box(0.0, 1.0, [light])}),
        **(extra or {}),
    }
    return spaces.Dict(entries, sampling_order=list(entries))


def tint(colors: np.ndarray) -> np.ndarray:
    """The "on target" colours: ``SUCCESS_TINT`` of the way to white."""
    colors = np.asarray(colors, np.float64)
    return colors + SUCCESS_TINT * (1.0 - colors)


class VisualFactors:
    """Writes agent colour, floor colours, light and camera angle into a compiled model.

    Built once per compiled model (it keeps the model's pristine floor texture and camera
    orientation). :meth:`apply` returns True when the floor texture (:attr:`floor_texture`)
    changed, which a live GL context only sees after the texture is uploaded again.
    """

    def __init__(self, model, mujoco):
        self._mj = mujoco
        self.model = model
        self._mats = [model.material(name).id for name in AGENT_MATERIALS]
        self._light = model.light(LIGHT).id
        self._cam = model.camera(RENDER_CAMERA).id
        self._quat0 = model.cam_quat[self._cam].copy()
        self.floor_texture = tex = model.texture(FLOOR_TEXTURE).id
        start = int(model.tex_adr[tex])
        n = int(model.tex_width[tex] * model.tex_height[tex] * model.tex_nchannel[tex])
        self._tex = model.tex_data[start : start + n].reshape(-1, int(model.tex_nchannel[tex]))  # a view
        pristine = self._tex[:, :3].copy()
        self._masks = [np.all(pristine == _texel(c), axis=1) for c in FLOOR_COLORS]
        self._floor = np.asarray(FLOOR_COLORS, np.float64)

    def apply(self, agent_color, floor_colors, intensity, angle_delta) -> bool:
        m = self.model
        m.mat_rgba[self._mats, :3] = np.asarray(agent_color, np.float64)
        m.light_diffuse[self._light] = float(np.asarray(intensity).reshape(-1)[0])
        yaw, pitch = np.radians(np.asarray(angle_delta, np.float64).reshape(-1)[:2])
        m.cam_quat[self._cam] = _rotate(self._mj, self._quat0, yaw, pitch)
        floor = np.asarray(floor_colors, np.float64)
        if np.array_equal(floor, self._floor):
            return False
        for mask, color in zip(self._masks, floor, strict=True):
            self._tex[mask, :3] = _texel(color)
        self._floor = floor.copy()
        return True


def _texel(color) -> np.ndarray:
    """A colour as MuJoCo writes it into a builtin texture (``255 * c`` truncated)."""
    return (255.0 * np.asarray(color, np.float64)).astype(np.uint8)


def _rotate(mujoco, quat0: np.ndarray, yaw: float, pitch: float) -> np.ndarray:
    """``R_x(pitch) @ R_z(yaw) @ quat0`` (rotations about the world axes), as a (w, x, y, z) quaternion."""
    qz, qx, tmp, out = np.zeros(4), np.zeros(4), np.zeros(4), np.zeros(4)
    mujoco.mju_axisAngle2Quat(qz, np.array([0.0, 0.0, 1.0]), yaw)
    mujoco.mju_axisAngle2Quat(qx, np.array([1.0, 0.0, 0.0]), pitch)
    mujoco.mju_mulQuat(tmp, qz, np.asarray(quat0, np.float64))
    mujoco.mju_mulQuat(out, qx, tmp)
    return out


class CubeSizes:
    """Writes cube half-extents into a compiled model: geom sizes, bounding spheres and boxes,
    masses and inertias (scaled from the compiled cube's, density unchanged), then
    ``mj_setConst``; this gives the numbers of a model compiled with those sizes (to 1e-12), so
    no recompilation is needed. The target (mocap) cubes follow their cube."""

    def __init__(self, model, mujoco, geoms: list[list[int]], target_geoms: list[list[int]]):
        self._mj, self.model = mujoco, model
        self._geoms = [list(g) + list(t) for g, t in zip(geoms, target_geoms, strict=True)]
        self._bodies = [sorted({int(model.geom_bodyid[g]) for g in group}) for group in self._geoms]
        self._size0 = float(model.geom_size[self._geoms[0][0], 0])
        self._mass0 = {b: (float(model.body_mass[b]), model.body_inertia[b].copy()) for bs in self._bodies for b in bs}
        self._applied: np.ndarray | None = None

    def apply(self, sizes) -> None:
        sizes = np.asarray(sizes, np.float64)
        if self._applied is not None and np.array_equal(sizes, self._applied):
            return
        m = self.model
        for s, geoms, bodies in zip(sizes.tolist(), self._geoms, self._bodies, strict=True):
            k = s / self._size0
            m.geom_size[geoms] = s
            m.geom_rbound[geoms] = np.sqrt(3.0) * s
            m.geom_aabb[geoms, 3:] = s
            for b in bodies:
                mass, inertia = self._mass0[b]
                m.body_mass[b], m.body_inertia[b] = mass * k**3, inertia * k**5
                if m.body_bvhnum[b] > 0:
                    m.bvh_aabb[m.body_bvhadr[b], 3:] = s
        self._mj.mj_setConst(m, self._mj.MjData(m))
        self._applied = sizes.copy()
