"""The Fetch simulation, written against ``mujoco`` directly (no ``gymnasium_robotics`` code runs).

Gymnasium-Robotics' Fetch tasks (v4, the ``mujoco`` bindings) as facts: its MJCF models and
meshes are read from the installed ``gymnasium_robotics`` package; the control and observation
rules are those of its ``MujocoFetchEnv``:

- **Setup** (once per model): the task's initial joint positions, the mocap weld reset, then the
  gripper driven to ``(-0.498, 0.005, -0.431 + gripper_extra_height)`` from its start by 10
  control steps; that state is the start of every episode.
- **Action** ``(dx, dy, dz, grip)`` in ``[-1, 1]``: the mocap body is put on the gripper's pose,
  moved by ``0.05 * (dx, dy, dz)`` with the gripper pointing down, and the finger actuators
  (Pick-and-place only) aim at their current opening plus ``grip``; then 20 MuJoCo steps of
  2 ms (one control step is 0.04 s). Tasks with a blocked gripper close the fingers after each step.
- **Observation** (10 numbers for Reach, 25 with an object): gripper position, object position,
  object position relative to the gripper, the two finger positions, object orientation (Euler),
  object linear velocity relative to the gripper's and angular velocity, gripper linear velocity,
  finger velocities (velocities times the control step).
- **Achieved goal**: the gripper position (Reach) or the object position.

Enum values are compared as ints here: ``gymnasium_robotics.utils.mujoco_utils.set_joint_qpos`` asserts
``joint_type in (mjJNT_HINGE, mjJNT_SLIDE)``, which fails under mujoco 3.17, where
``mujoco.mjtJoint.mjJNT_SLIDE == np.int32(2)`` is False (``np.int32(2) == mujoco.mjtJoint.mjJNT_SLIDE``
is True, and ``in`` asks the tuple's members), so ``gymnasium.make("FetchReach-v4")`` cannot be
built there (Gymnasium-Robotics 1.4.2).
"""

from __future__ import annotations

import copy
import importlib.util
import os
from dataclasses import dataclass, field

import mujoco
import numpy as np

N_SUBSTEPS = 20
POS_SCALE = 0.05  # metres of mocap motion per unit of action
DOWN_QUAT = np.array([1.0, 0.0, 1.0, 0.0])  # added to the gripper quaternion each step (gripper pointing down)
DISTANCE_THRESHOLD = 0.05
CAMERA = "swm_view"
#: Gymnasium-Robotics' Fetch render camera (a free camera): distance, azimuth, elevation (degrees), look-at point
CAMERA_DISTANCE, CAMERA_AZIMUTH, CAMERA_ELEVATION = 2.5, 132.0, -14.0
CAMERA_LOOKAT = np.array([1.3, 0.75, 0.55])
_QPOS_WIDTH = {0: 7, 1: 4, 2: 1, 3: 1}  # mjtJoint free, ball, slide, hinge
_QVEL_WIDTH = {0: 6, 1: 3, 2: 1, 3: 1}
SETTLE_STEPS = 40  # control steps allowed to bring the gripper onto a target (contacts off)
SETTLE_TOL = 1e-3


@dataclass(frozen=True)
class TaskSpec:
    """One Fetch task as Gymnasium-Robotics defines it."""

    name: str
    xml: str
    has_object: bool
    block_gripper: bool
    gripper_extra_height: float
    target_in_the_air: bool
    target_offset: tuple[float, float, float]
    obj_range: float
    target_range: float
    initial_qpos: dict[str, tuple[float, ...]] = field(default_factory=dict)


_ROBOT_START = {"robot0:slide0": (0.405,), "robot0:slide1": (0.48,), "robot0:slide2": (0.0,)}
_OBJECT_START = {"object0:joint": (1.25, 0.53, 0.4, 1.0, 0.0, 0.0, 0.0)}
TASKS: dict[str, TaskSpec] = {
    "Reach": TaskSpec(
        "Reach",
        "reach.xml",
        False,
        True,
        0.2,
        True,
        (0.0, 0.0, 0.0),
        0.15,
        0.15,
        {**_ROBOT_START, "robot0:slide0": (0.4049,)},
    ),
    "Push": TaskSpec(
        "Push", "push.xml", True, True, 0.0, False, (0.0, 0.0, 0.0), 0.15, 0.15, {**_ROBOT_START, **_OBJECT_START}
    ),
    "Slide": TaskSpec(
        "Slide",
        "slide.xml",
        True,
        True,
        -0.02,
        False,
        (0.4, 0.0, 0.0),
        0.1,
        0.3,
        {**_ROBOT_START, "robot0:slide0": (0.05,), "object0:joint": (1.7, 1.1, 0.41, 1.0, 0.0, 0.0, 0.0)},
    ),
    "PickAndPlace": TaskSpec(
        "PickAndPlace",
        "pick_and_place.xml",
        True,
        False,
        0.2,
        True,
        (0.0, 0.0, 0.0),
        0.15,
        0.15,
        {**_ROBOT_START, **_OBJECT_START},
    ),
}


def assets_dir() -> str:
    """The Fetch MJCF folder of the installed ``gymnasium_robotics`` (located, not imported)."""
    spec = importlib.util.find_spec("gymnasium_robotics")
    if spec is None or not spec.submodule_search_locations:
        raise ModuleNotFoundError("gymnasium_robotics")
    return os.path.join(list(spec.submodule_search_locations)[0], "envs", "assets", "fetch")


def camera_pose(azimuth: float, elevation: float) -> tuple[np.ndarray, np.ndarray]:
    """(pos, quat) of a fixed camera that sees what MuJoCo's free camera sees at ``azimuth`` /
    ``elevation`` (degrees), :data:`CAMERA_DISTANCE` from :data:`CAMERA_LOOKAT`."""
    az, el = np.radians(azimuth), np.radians(elevation)
    forward = np.array([np.cos(el) * np.cos(az), np.cos(el) * np.sin(az), np.sin(el)])
    right = np.cross(forward, [0.0, 0.0, 1.0])
    right /= np.linalg.norm(right)
    back = -forward
    up = np.cross(back, right)
    quat = np.zeros(4)
    mujoco.mju_mat2Quat(quat, np.stack([right, up, back], axis=1).reshape(-1))
    return CAMERA_LOOKAT - CAMERA_DISTANCE * forward, quat


_MODELS: dict[str, mujoco.MjModel] = {}
_MESH_MODELS: dict[tuple[str, str], mujoco.MjModel | None] = {}


def _spec(task: str) -> mujoco.MjSpec:
    spec = mujoco.MjSpec.from_file(os.path.join(assets_dir(), TASKS[task].xml))
    pos, quat = camera_pose(CAMERA_AZIMUTH, CAMERA_ELEVATION)
    spec.worldbody.add_camera(name=CAMERA, pos=pos, quat=quat)
    return spec


def load_model(task: str) -> mujoco.MjModel:
    """A fresh copy of ``task``'s compiled model, with the render camera :data:`CAMERA` added
    (compiled once per process)."""
    if task not in _MODELS:
        _MODELS[task] = _spec(task).compile()
    return copy.deepcopy(_MODELS[task])


def mesh_model(task: str, quality: str) -> mujoco.MjModel | None:
    """The lighter model the GL context of ``task`` draws at ``quality`` (``MjRenderer(mesh_model=...)``):
    the Fetch meshes (34k faces, most of a CPU frame's cost) decimated as the OGBench arm's
    (:mod:`stable_worldmodel.envs.ogbench.meshes`: ``"low"`` 5 %, ``"medium"`` 10 % of the large
    meshes' faces; about twice as fast to draw and to set up); None at ``"high"`` (the exact meshes,
    upstream's picture) or without ``fast-simplification``. Compiled once per process."""
    from ..._optional import is_available
    from ..ogbench import meshes

    key = (task, quality)
    if key not in _MESH_MODELS:
        ratio = meshes.MESH_DETAIL.get(quality)
        if ratio is None or not is_available("fast_simplification"):
            _MESH_MODELS[key] = None
        else:
            xml, root = _spec(task).to_xml(), assets_dir()
            for attr, folder in (("meshdir", "../stls/fetch"), ("texturedir", "../textures")):
                xml = xml.replace(f'{attr}="{folder}"', f'{attr}="{os.path.normpath(os.path.join(root, folder))}"')
            _MESH_MODELS[key] = meshes.render_mesh_model(load_model(task), xml, {}, ratio)
    return _MESH_MODELS[key]


def joint_qpos(model: mujoco.MjModel, name: str) -> slice:
    """The ``qpos`` slice of joint ``name``."""
    j = model.joint(name).id
    start = int(model.jnt_qposadr[j])
    return slice(start, start + _QPOS_WIDTH[int(model.jnt_type[j])])


def joint_qvel(model: mujoco.MjModel, name: str) -> slice:
    """The ``qvel`` slice of joint ``name``."""
    j = model.joint(name).id
    start = int(model.jnt_dofadr[j])
    return slice(start, start + _QVEL_WIDTH[int(model.jnt_type[j])])


def mat2euler(mat: np.ndarray) -> np.ndarray:
    """Gymnasium-Robotics' Euler angles of a rotation matrix (its ``rotations.mat2euler``)."""
    m = np.asarray(mat, np.float64).reshape(3, 3)
    cy = np.hypot(m[2, 2], m[1, 2])
    if cy > np.finfo(np.float64).eps * 4.0:
        return np.array([-np.arctan2(m[1, 2], m[2, 2]), -np.arctan2(-m[0, 2], cy), -np.arctan2(m[0, 1], m[0, 0])])
    return np.array([0.0, -np.arctan2(-m[0, 2], cy), -np.arctan2(-m[1, 0], m[1, 1])])


def euler2quat(euler: np.ndarray) -> np.ndarray:
    """The inverse of :func:`mat2euler`: the rotation ``Rx(a) Ry(b) Rz(c)`` as a w-first quaternion."""
    quat = np.array([1.0, 0.0, 0.0, 0.0])
    for axis, angle in enumerate(np.asarray(euler, np.float64).reshape(3)):
        turn = np.zeros(4)
        turn[0], turn[1 + axis] = np.cos(angle / 2.0), np.sin(angle / 2.0)
        mujoco.mju_mulQuat(quat, quat.copy(), turn)
    return quat


class FetchSim:
    """One Fetch task's model and data, stepped and observed as Gymnasium-Robotics does."""

    def __init__(self, task: str):
        self.spec = TASKS[task]
        self.model = load_model(task)
        self.data = mujoco.MjData(self.model)
        m = self.model
        self.dt = N_SUBSTEPS * float(m.opt.timestep)
        self.grip_site = m.site("robot0:grip").id
        self.gripper_body = m.body("robot0:gripper_link").id
        self.target_site = m.site("target0").id
        self.robot_joints = [m.joint(i).name for i in range(m.njnt) if m.joint(i).name.startswith("robot")]
        self.finger_qpos = [joint_qpos(m, f"robot0:{s}_gripper_finger_joint").start for s in ("r", "l")]
        self.finger_qvel = [joint_qvel(m, f"robot0:{s}_gripper_finger_joint").start for s in ("r", "l")]
        self.robot_qpos = np.array([joint_qpos(m, n).start for n in self.robot_joints])
        self.robot_qvel = np.array([joint_qvel(m, n).start for n in self.robot_joints])
        self.actuator_qpos = np.array([m.jnt_qposadr[m.actuator_trnid[i, 0]] for i in range(m.nu)], int)
        self.actuator_biased = np.array([int(m.actuator_biastype[i]) != 0 for i in range(m.nu)], bool)
        if self.spec.has_object:
            self.object_qpos, self.object_qvel = joint_qpos(m, "object0:joint"), joint_qvel(m, "object0:joint")
            self.object_site, self.object_geom = m.site("object0").id, m.geom("object0").id
        self._jacp, self._jacr = np.zeros((3, m.nv)), np.zeros((3, m.nv))
        self._setup()

    # -- setup --------------------------------------------------------------------------------------
    def _setup(self) -> None:
        m, d = self.model, self.data
        for name, value in self.spec.initial_qpos.items():
            d.qpos[joint_qpos(m, name)] = value
        for i in range(m.neq):  # reset the mocap weld
            if int(m.eq_type[i]) == int(mujoco.mjtEq.mjEQ_WELD):
                m.eq_data[i, :7] = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 1.0)
        mujoco.mj_forward(m, d)
        target = np.array([-0.498, 0.005, -0.431 + self.spec.gripper_extra_height]) + d.site_xpos[self.grip_site]
        d.mocap_pos[0], d.mocap_quat[0] = target, DOWN_QUAT
        for _ in range(10):
            mujoco.mj_step(m, d, nstep=N_SUBSTEPS)
        self.initial_time = float(d.time)
        self.initial_qpos, self.initial_qvel = d.qpos.copy(), d.qvel.copy()
        self.initial_gripper_xpos = d.site_xpos[self.grip_site].copy()
        self.height_offset = float(d.site_xpos[self.object_site][2]) if self.spec.has_object else 0.0

    def reset(self, data: mujoco.MjData | None = None) -> None:
        """Back to the start state of every episode (Gymnasium-Robotics' ``_reset_sim`` before the
        object is placed)."""
        d = self.data if data is None else data
        mujoco.mj_resetData(self.model, d)
        d.time = self.initial_time
        d.qpos[:] = self.initial_qpos
        d.qvel[:] = self.initial_qvel

    def place_mocap_on_gripper(self, data: mujoco.MjData | None = None) -> None:
        """The mocap body on the gripper's pose (what every action starts from); needs kinematics."""
        d = self.data if data is None else data
        d.mocap_pos[0] = d.xpos[self.gripper_body]
        d.mocap_quat[0] = d.xquat[self.gripper_body] + DOWN_QUAT

    # -- control ------------------------------------------------------------------------------------
    def step(self, action: np.ndarray) -> None:
        """One control step of ``action`` (already clipped to [-1, 1], 4 numbers)."""
        m, d = self.model, self.data
        grip = 0.0 if self.spec.block_gripper else float(action[3])
        for i in range(m.nu):
            d.ctrl[i] = d.qpos[self.actuator_qpos[i]] + grip if self.actuator_biased[i] else grip
        self.place_mocap_on_gripper()
        d.mocap_pos[0] += POS_SCALE * np.asarray(action[:3], np.float64)
        mujoco.mj_step(m, d, nstep=N_SUBSTEPS)
        if self.spec.block_gripper:
            d.qpos[self.finger_qpos] = 0.0
            mujoco.mj_forward(m, d)

    def move_gripper(self, target: np.ndarray, data: mujoco.MjData | None = None) -> float:
        """Drive the arm (contacts off, everything else kept) until the gripper is at ``target``;
        returns the remaining distance. The object and fingers are put back where they were."""
        m, d = self.model, self.data if data is None else data
        keep_q = d.qpos[self.object_qpos].copy() if self.spec.has_object else None
        fingers = d.qpos[self.finger_qpos].copy()
        flags = m.opt.disableflags
        m.opt.disableflags = flags | int(mujoco.mjtDisableBit.mjDSBL_CONTACT)
        try:
            # the mocap holds the gripper link; the grip site sits a little ahead of it
            offset = d.site_xpos[self.grip_site] - d.xpos[self.gripper_body]
            d.mocap_pos[0], d.mocap_quat[0] = target - offset, DOWN_QUAT
            err = np.inf
            for _ in range(SETTLE_STEPS):
                mujoco.mj_step(m, d, nstep=N_SUBSTEPS)
                if keep_q is not None:
                    d.qpos[self.object_qpos] = keep_q
                d.qpos[self.finger_qpos] = fingers
                mujoco.mj_forward(m, d)
                miss = target - d.site_xpos[self.grip_site]
                err = float(np.linalg.norm(miss))
                level = abs(float(np.dot(d.xquat[self.gripper_body], DOWN_QUAT))) / np.sqrt(2.0)
                if err < SETTLE_TOL and level > 1.0 - SETTLE_TOL:
                    break
                d.mocap_pos[0] += miss
        finally:
            m.opt.disableflags = flags
        d.qvel[:] = 0.0
        d.qacc_warmstart[:] = 0.0
        mujoco.mj_forward(m, d)
        self.place_mocap_on_gripper(d)
        mujoco.mj_forward(m, d)
        return err

    # -- observation --------------------------------------------------------------------------------
    def observation(self, data: mujoco.MjData | None = None) -> tuple[np.ndarray, np.ndarray]:
        """(observation, achieved goal) as Gymnasium-Robotics' Fetch computes them."""
        d = self.data if data is None else data
        grip_pos = d.site_xpos[self.grip_site].copy()
        grip_velp = self._site_vel(d, self.grip_site)[0] * self.dt
        gripper_state = d.qpos[self.robot_qpos[-2:]].copy()
        gripper_vel = d.qvel[self.robot_qvel[-2:]] * self.dt
        if not self.spec.has_object:
            obs = np.concatenate([grip_pos, gripper_state, grip_velp, gripper_vel])
            return obs, grip_pos.copy()
        object_pos = d.site_xpos[self.object_site].copy()
        object_rot = mat2euler(d.site_xmat[self.object_site])
        velp, velr = self._site_vel(d, self.object_site)
        object_velp = velp * self.dt - grip_velp
        object_velr = velr * self.dt
        obs = np.concatenate(
            [
                grip_pos,
                object_pos,
                object_pos - grip_pos,
                gripper_state,
                object_rot,
                object_velp,
                object_velr,
                grip_velp,
                gripper_vel,
            ]
        )
        return obs, object_pos

    def _site_vel(self, d: mujoco.MjData, site: int) -> tuple[np.ndarray, np.ndarray]:
        mujoco.mj_jacSite(self.model, d, self._jacp, self._jacr, site)
        return self._jacp @ d.qvel, self._jacr @ d.qvel

    def show_target(self, goal: np.ndarray) -> None:
        """Put the red target sphere on ``goal`` (takes effect at the next kinematics)."""
        body = self.model.site_bodyid[self.target_site]
        self.model.site_pos[self.target_site] = np.asarray(goal) - self.data.xpos[body]
