"""Record upstream 0.1.1 SimplePointMaze reference numbers (run in the 0.1.1 venv)."""

import sys
import warnings

warnings.filterwarnings("ignore")
import cv2
import numpy as np

from stable_worldmodel.envs.simple_point_maze import SimplePointMazeEnv as E

env = E(render_mode="rgb_array")
small = lambda f, n: cv2.resize(f, (n, n), interpolation=cv2.INTER_AREA)
rng = np.random.default_rng(0)
out = {}


def play(name, acts, frames_at=(0, 5, 10)):
    S, R, T, F = [env.state.astype(np.float64)], [], [], {0: env.render()}
    for t, a in enumerate(acts, 1):
        o, r, te, tr, info = env.step(a)
        S.append(np.asarray(o, np.float64))
        R.append(r)
        T.append(te)
        if t in frames_at:
            F[t] = env.render()
    out[name + "/actions"] = np.asarray(acts, np.float32)
    out[name + "/states"] = np.array(S)
    out[name + "/rewards"] = np.array(R)
    out[name + "/terminated"] = np.array(T)
    out[name + "/frame_steps"] = np.array(sorted(F))
    out[name + "/frames64"] = np.stack([small(F[k], 64) for k in sorted(F)])
    out[name + "/frame224"] = small(F[max(F)], 224)


for case, var in (("default", None), ("all", ["all"])):
    for seed in (0, 3):
        name = f"{case}_seed{seed}"
        obs, info = env.reset(seed=seed, options=None if var is None else {"variation": var})
        out[name + "/obs0"] = np.asarray(obs)
        out[name + "/walls_positions"] = env.variation_space["walls"]["positions"].value
        out[name + "/walls_number"] = np.array(env.variation_space["walls"]["number"].value)
        out[name + "/agent_radius"] = np.array(env.variation_space["agent"]["radius"].value)
        out[name + "/goal_position"] = env.variation_space["goal"]["position"].value
        out[name + "/goal64"] = small(info["goal"], 64)
        out[name + "/goal224"] = small(info["goal"], 224)
        play(name, rng.uniform(-0.25, 0.25, (12, 2)).astype(np.float32))
# fixed start / goal: a straight line into a wall, and one reaching the goal
for name, s0, goal, acts in (
    ("line", [0.5, 2.5], [4.5, 4.5], np.tile([0.2, 0.0], (15, 1))),
    ("reach", [4.5, 3.9], [4.5, 4.5], np.tile([0.0, 0.2], (5, 1))),
):
    env.reset(seed=0, options={"variation": []})
    env.state = np.asarray(s0, np.float32)
    env.variation_space["goal"]["position"].set_value(np.asarray(goal, np.float32))
    out[name + "/start"] = np.asarray(s0, np.float32)
    out[name + "/goal"] = np.asarray(goal, np.float32)
    play(name, acts.astype(np.float32), frames_at=(0, len(acts)))
np.savez_compressed(sys.argv[1], **out)
print({k: v.tolist() for k, v in out.items() if k.endswith(("rewards", "terminated"))})
