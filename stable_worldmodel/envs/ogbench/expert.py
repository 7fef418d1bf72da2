"""Scripted expert of ``swm/OGBCube-v0`` and ``swm/OGBScene-v0``, built on OGBench's Markov oracles.

OGBench's oracles (``ogbench.manipspace.oracles.markov``) each solve one subtask (move one cube,
press one button, slide the drawer or the window) from the env's ``proprio.*`` and
``privileged.*`` infos (OGBench's ``proprio/*``, ``privileged/*``: :mod:`.infokeys`). This
expert keeps, per env, the subtask in progress and its oracle, and when the oracle is done
picks the next subtask from the current infos:

- **Cube**: among the cubes farther than 4 cm from their targets and not covered by another
  cube, the one with the lowest target (stacks are built bottom-up), lowest index first.
- **Scene**: a drawer off its target (more than 4 cm) first (pressing button 0 first when it is
  locked), then the window likewise (button 1), then the buttons still different from the goal,
  then the cube.

In ``mode="data_collection"`` (the infos carry OGBench's ``privileged.target_task``), it does what
upstream 0.1.1's expert does there: the oracle of the env's current subtask acts until done, then
the expert asks that env for the next subtask, ``set_new_target(p_stack=p)`` (through the World's
``call_each``, so it works in worker processes too; a policy without an env keeps the subtask),
with ``p`` drawn per episode as upstream: 0 for one cube, ``U(0, 0.25)`` for two, ``U(0.05,
0.35)`` for three, ``U(0.1, 0.5)`` for four, 0.5 for Scene.

Noise, as OGBench's data collection (which uses ``noise=0.1``; the default 0 gives clean
demonstrations, as the other swm experts): with probability ``p_random_action`` a uniform random
action, otherwise the oracle's action plus Gaussian noise of std ``noise``, clipped to [-1, 1]. The
oracles' final arm poses and the noise come from the expert's own generator (``seed``); the
global ``np.random`` is left as it was. A new episode of env ``b`` (``step_idx`` 0, or ``time`` 0
without the World's keys) starts a fresh plan.
"""

from __future__ import annotations

from types import SimpleNamespace
from typing import Any

import numpy as np

from ... import keys
from ..._optional import require
from ...errors import ConfigError
from ...policy import ExpertPolicy
from . import infokeys

_ORACLES = "ogbench.manipspace.oracles.markov"
SUCCESS_DISTANCE = 0.04
COVER_XY, COVER_Z = 0.02, 0.01  # a cube within COVER_XY (xy) and above another covers it
STACK_P = {1: (0.0, 0.0), 2: (0.0, 0.25), 3: (0.05, 0.35), 4: (0.1, 0.5)}  # cubes -> p_stack range (upstream)
SCENE_P_STACK = 0.5
TARGET_TASK = "privileged/target_task"
ARM_BOUNDS = {
    "cube": np.array([[0.25, -0.35, 0.2], [0.6, 0.35, 0.35]]),
    "scene": np.array([[0.25, -0.2, 0.2], [0.6, 0.2, 0.35]]),
}


class OGBenchExpert(ExpertPolicy):
    """Batched OGBench expert (module docstring): ``get_action(infos) -> (B, 5)`` float32."""

    def __init__(
        self,
        env_id: str = "swm/OGBCube-v0",
        noise: float = 0.0,
        p_random_action: float = 0.0,
        min_norm: float = 0.4,
        seed: int | None = None,
        **kwargs: Any,
    ):
        if not np.isfinite(noise) or noise < 0:
            raise ConfigError(f"OGBenchExpert requires noise >= 0, got {noise!r}")
        if not 0.0 <= p_random_action <= 1.0:
            raise ConfigError(f"OGBenchExpert requires p_random_action in [0, 1], got {p_random_action!r}")
        if not min_norm >= 0:
            raise ConfigError(f"OGBenchExpert requires min_norm >= 0, got {min_norm!r}")
        super().__init__(env_id=env_id, noise=float(noise), seed=seed, **kwargs)
        self.p_random_action = float(p_random_action)
        self.min_norm = float(min_norm)
        self.rng = np.random.default_rng(seed)
        self._plans: list[dict[str, Any]] = []
        markov = {
            name: require(f"{_ORACLES}.{name}_markov", extra="mujoco", purpose="OGBenchExpert")
            for name in ("cube", "button", "drawer", "window")
        }
        self._oracle_cls = {
            "cube": markov["cube"].CubeMarkovOracle,
            "button": markov["button"].ButtonMarkovOracle,
            "drawer": markov["drawer"].DrawerMarkovOracle,
            "window": markov["window"].WindowMarkovOracle,
        }

    def get_action(self, infos: dict[str, Any], **kwargs: Any) -> np.ndarray:
        """``infos``: the World's batched infos, entries ``(B, T, ...)``; returns ``(B, 5)`` float32."""
        names = [k for k in infos if infokeys.is_ogbench_entry(k)]
        n_env = len(infos[infokeys.ours("proprio/effector_pos")])
        if len(self._plans) != n_env:
            self._plans = [{} for _ in range(n_env)]
        kind = "scene" if infokeys.ours("privileged/drawer_pos") in infos else "cube"
        out = np.zeros((n_env, 5), np.float32)
        for b in range(n_env):
            info = {infokeys.ogbench(k): np.asarray(infos[k][b])[-1] for k in names}  # OGBench's names
            if self._episode_start(infos, b):
                self._plans[b] = {}
            if TARGET_TASK in info:
                action = self._act_collecting(b, self._plans[b], info, kind)
            else:
                action = self._act(self._plans[b], info, kind)
            out[b] = self._noisy(action)
        return out

    @staticmethod
    def _episode_start(infos: dict[str, Any], b: int) -> bool:
        if keys.STEP_IDX in infos:
            return int(np.asarray(infos[keys.STEP_IDX][b]).reshape(-1)[-1]) == 0
        return float(np.asarray(infos["time"][b]).reshape(-1)[-1]) == 0.0

    def _act(self, plan: dict[str, Any], info: dict[str, np.ndarray], kind: str) -> np.ndarray:
        oracle = plan.get("oracle")
        if oracle is None or oracle.done:
            plan["task"] = self._next_task(info, kind)
            if plan["task"] is None:
                plan["oracle"] = None
                return np.zeros(5)
            plan["oracle"] = oracle = self._make_oracle(plan["task"][0], self._oracle_info(plan["task"], info), kind)
        return np.asarray(oracle.select_action(None, self._oracle_info(plan["task"], info)), np.float64)

    def _act_collecting(self, b: int, plan: dict[str, Any], info: dict[str, np.ndarray], kind: str) -> np.ndarray:
        """Data collection: the env's own subtask; a new one from env ``b`` when the oracle is done."""
        if plan.get("oracle") is None:
            n_cubes = sum(1 for k in info if k.startswith("privileged/block_") and k.endswith("_pos"))
            low, high = (SCENE_P_STACK,) * 2 if kind == "scene" else STACK_P.get(n_cubes, (SCENE_P_STACK,) * 2)
            plan["p_stack"] = float(self.rng.uniform(low, high)) if high > low else low
            plan["oracle"] = self._make_oracle(str(info[TARGET_TASK]), info, kind)
        oracle = plan["oracle"]
        action = np.asarray(oracle.select_action(None, info), np.float64)
        if oracle.done:
            new_info = self._next_subtask(b, plan["p_stack"])
            if new_info is not None:
                plan["oracle"] = self._make_oracle(str(new_info[TARGET_TASK]), new_info, kind)
        return action

    def _next_subtask(self, b: int, p_stack: float) -> dict[str, np.ndarray] | None:
        """``set_new_target(p_stack=...)`` on env ``b``; its info with OGBench's names (None without an env)."""
        env = self.env
        if env is None:
            return None
        if callable(getattr(env, "call_each", None)):
            reply = env.call_each("set_new_target", [()], [{"p_stack": p_stack}], env_ids=[b])[0]
        else:
            target = getattr(env, "unwrapped", env)
            if not callable(getattr(target, "set_new_target", None)):
                return None
            reply = target.set_new_target(p_stack=p_stack)
        return {infokeys.ogbench(k): np.asarray(v) for k, v in reply[1].items() if infokeys.is_ogbench_entry(k)}

    def _noisy(self, action: np.ndarray) -> np.ndarray:
        if self.p_random_action and self.rng.random() < self.p_random_action:
            return self.rng.uniform(-1.0, 1.0, 5)
        if self.noise:
            action = action + self.rng.normal(0.0, self.noise, 5)
        return np.clip(action, -1.0, 1.0)

    # -- subtasks ---------------------------------------------------------------------------------
    @staticmethod
    def _cube_task(info: dict[str, np.ndarray]) -> tuple | None:
        n = sum(1 for k in info if k.startswith("privileged/target_block_") and k.endswith("_pos"))
        pos = np.array([info[f"privileged/block_{i}_pos"] for i in range(n)])
        target = np.array([info[f"privileged/target_block_{i}_pos"] for i in range(n)])
        todo = [i for i in range(n) if np.linalg.norm(pos[i] - target[i]) > SUCCESS_DISTANCE]
        covered = {
            i
            for i in todo
            for j in range(n)
            if j != i and pos[j, 2] > pos[i, 2] + COVER_Z and np.linalg.norm(pos[j, :2] - pos[i, :2]) < COVER_XY
        }
        free = [i for i in todo if i not in covered] or todo
        return ("cube", min(free, key=lambda i: (target[i, 2], i))) if free else None

    def _next_task(self, info: dict[str, np.ndarray], kind: str) -> tuple | None:
        if kind == "cube":
            return self._cube_task(info)
        buttons = [int(info[f"privileged/button_{i}_state"]) for i in range(2)]
        goal_buttons = np.asarray(info["privileged/target_button_states"]).astype(int).tolist()
        for lock, part in enumerate(("drawer", "window")):
            error = float(info[f"privileged/{part}_pos"][0] - info[f"privileged/target_{part}_pos"][0])
            if abs(error) > SUCCESS_DISTANCE:
                return ("button", lock, 1) if buttons[lock] == 0 else (part,)
        for i in range(2):
            if buttons[i] != goal_buttons[i]:
                return ("button", i, goal_buttons[i])
        return self._cube_task(info)

    def _oracle_info(self, task: tuple, info: dict[str, np.ndarray]) -> dict[str, Any]:
        """``info`` plus the single-target keys OGBench's oracle of ``task`` reads."""
        out = dict(info)
        if task[0] == "cube":
            i = task[1]
            out["privileged/target_block"] = i
            out["privileged/target_block_pos"] = info[f"privileged/target_block_{i}_pos"]
            out["privileged/target_block_yaw"] = info[f"privileged/target_block_{i}_yaw"]
        elif task[0] == "button":
            out["privileged/target_button"] = task[1]
            out["privileged/target_button_top_pos"] = info[f"privileged/button_{task[1]}_top_pos"]
            out["privileged/target_button_state"] = task[2]
        return out

    def _make_oracle(self, name: str, info: dict[str, Any], kind: str):
        """A fresh oracle of subtask kind ``name`` reset on ``info`` (OGBench's names, with the
        single-target keys); its final arm pose drawn from our generator (the global ``np.random``
        is restored after OGBench's ``reset`` draws from it)."""
        if name not in self._oracle_cls:
            raise ConfigError(f"OGBenchExpert has no oracle for subtask {name!r} (known: {sorted(self._oracle_cls)})")
        shim = SimpleNamespace(unwrapped=SimpleNamespace(_arm_sampling_bounds=ARM_BOUNDS[kind].copy()))
        oracle = self._oracle_cls[name](env=shim, min_norm=self.min_norm)
        saved = np.random.get_state()
        try:
            np.random.seed(int(self.rng.integers(0, 2**32 - 1)))
            oracle.reset(None, info)
        finally:
            np.random.set_state(saved)
        return oracle
