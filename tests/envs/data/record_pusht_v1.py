"""Record reference numbers of upstream 0.1.1's PushT into ``pusht_v1_upstream.npz`` / ``.json``.

Run with an interpreter that has the original ``stable_worldmodel==0.1.1`` installed, from a
directory outside this checkout (so the original package is imported)::

    cd /tmp && /path/to/peer011-venv/bin/python /work/main/tests/envs/data/record_pusht_v1.py

The tests in ``tests/envs/test_envs_upstream.py`` replay these numbers without the original.
"""

import json
import math
import os
import warnings

warnings.filterwarnings("ignore")
import gymnasium as gym  # noqa: E402
import numpy as np  # noqa: E402

import stable_worldmodel  # noqa: E402,F401

HERE = os.path.dirname(os.path.abspath(__file__))
GOAL = [256.0, 200.0, 256.0, 256.0, math.pi / 4, 0.0, 0.0]
rng = np.random.default_rng(1234)

# name: (start state, goal state, actions, variation_values or None, frame sizes)
CASES = {
    "push": ([256.0, 210.0, 256.0, 256.0, 0.0, 0.0, 0.0], GOAL, np.tile([[0.0, 0.4]], (15, 1)), None),
    "free": ([100.0, 100.0, 300.0, 300.0, 1.0, 0.0, 0.0], GOAL, rng.uniform(-1, 1, (12, 2)), None),
    "vel": ([200.0, 150.0, 350.0, 300.0, 2.5, 150.0, -80.0], GOAL, rng.uniform(-1, 1, (8, 2)), None),
    "wall": ([480.0, 480.0, 250.0, 250.0, 0.3, 0.0, 0.0], GOAL, np.tile([[1.0, 1.0]], (8, 1)), None),  # no clip at 512
    "big": ([200.0, 300.0, 260.0, 280.0, 0.0, 0.0, 0.0], GOAL, np.tile([[1.7, -0.2]], (6, 1)), None),  # beyond [-1, 1]
    "atgoal": ([256.0, 200.0, 256.0, 256.0, math.pi / 4 + 0.1, 0.0, 0.0], GOAL, np.zeros((2, 2)), None),
    "shape_L": (
        [120.0, 120.0, 300.0, 300.0, 0.5, 0.0, 0.0],
        GOAL,
        np.tile([[0.6, 0.6]], (12, 1)),
        {"block.shape": 1, "block.scale": 35.0, "agent.scale": 30.0},
    ),
    "shape_plus": (
        [120.0, 300.0, 300.0, 300.0, 0.2, 0.0, 0.0],
        GOAL,
        np.tile([[0.8, 0.0]], (12, 1)),
        {"block.shape": 7, "agent.shape": 4, "agent.scale": 20.0},
    ),
    "colors": (
        [150.0, 150.0, 300.0, 300.0, 1.2, 0.0, 0.0],
        [400.0, 400.0, 200.0, 200.0, 0.7, 0.0, 0.0],
        np.zeros((1, 2)),
        {
            "agent.color": [200, 30, 30],
            "block.color": [20, 180, 60],
            "goal.color": [250, 200, 10],
            "background.color": [30, 30, 60],
            "goal.angle": 1.0,
            "goal.position": [300.0, 200.0],
        },
    ),
}
FRAME_SIZES = (64, 224)


def factors(vs, prefix=""):
    out = {}
    for k, v in vs.spaces.items():
        name = prefix + k
        if isinstance(v, gym.spaces.Dict):
            out.update(factors(v, name + "."))
            continue
        d = {"type": type(v).__name__, "default": np.asarray(v.init_value).tolist()}
        if isinstance(v, gym.spaces.Box):
            d.update(
                low=np.asarray(v.low).tolist(),
                high=np.asarray(v.high).tolist(),
                dtype=str(v.dtype),
                shape=list(v.shape),
            )
        if isinstance(v, gym.spaces.Discrete):
            d.update(n=int(v.n), start=int(v.start))
        out[name] = d
    return out


def run(env_id, cases, arrays, meta):
    for name, (start, goal, actions, values) in cases.items():
        key = f"{env_id.split('/')[1]}/{name}"
        frames = {s: [] for s in FRAME_SIZES}
        for size in FRAME_SIZES:
            env = gym.make(env_id, resolution=size).unwrapped
            options = {"state": np.array(start), "goal_state": np.array(goal)}
            if values:  # upstream wants arrays (it calls .tolist() on colors)
                options["variation_values"] = {
                    k: np.asarray(v, np.uint8 if k.endswith("color") else np.float32 if k.endswith("scale") else None)
                    for k, v in values.items()
                }
            obs, info = env.reset(seed=0, options=options)
            states, rewards, terms, contacts = [obs["state"]], [], [], [info["n_contacts"]]
            frames[size].append(env.render())
            if size == FRAME_SIZES[0]:
                meta[key + "/goal_frame_sum"] = int(info["goal"].astype(np.int64).sum())
                arrays[key + "/goal@64"] = info["goal"]
            for a in actions:
                obs, r, term, trunc, info = env.step(a)
                states.append(obs["state"])
                rewards.append(r)
                terms.append(term)
                contacts.append(info["n_contacts"])
                frames[size].append(env.render())
            env.close()
        arrays[key + "/actions"] = np.asarray(actions)
        arrays[key + "/start"] = np.asarray(start, np.float64)
        arrays[key + "/goal"] = np.asarray(goal, np.float64)
        arrays[key + "/states"] = np.asarray(states)
        arrays[key + "/rewards"] = np.asarray(rewards, np.float64)
        arrays[key + "/terminated"] = np.asarray(terms, bool)
        arrays[key + "/n_contacts"] = np.asarray(contacts, np.int64)
        arrays[key + "/frames@64"] = np.asarray(frames[64], np.uint8)
        arrays[key + "/frames@224"] = np.asarray(frames[224], np.uint8)[[0, -1]]  # first and last only
        meta[key + "/values"] = values


def main():
    arrays, meta = {}, {}
    run("swm/PushT-v1", CASES, arrays, meta)
    dcases = {
        "grid": (
            [256.0, 210.0, 256.0, 256.0, 0.0, 0.0, 0.0],
            GOAL,
            np.array([[15, 4], [15, 4], [8, 0], [3, 12], [0, 7], [15, 8], [10, 13], [12, 2]]),
            None,
        ),
    }
    run("swm/PushT-Discrete-v1", dcases, arrays, meta)
    env = gym.make("swm/PushT-v1").unwrapped
    obs, info = env.reset(seed=3)
    meta["factors"] = factors(env.variation_space)
    meta["info_keys"] = sorted(info)
    meta["env_name"] = info["env_name"]
    meta["obs_space"] = {
        k: [np.asarray(v.low).tolist(), np.asarray(v.high).tolist()] for k, v in env.observation_space.spaces.items()
    }
    denv = gym.make("swm/PushT-Discrete-v1").unwrapped
    meta["discrete_nvec"] = denv.action_space.nvec.tolist()
    meta["dequantized"] = {
        f"{i},{j}": denv.quantizer.dequantize(np.array([i, j])).tolist()
        for i, j in [(0, 0), (15, 0), (7, 4), (3, 12), (15, 15)]
    }
    np.savez_compressed(os.path.join(HERE, "pusht_v1_upstream.npz"), **arrays)
    with open(os.path.join(HERE, "pusht_v1_upstream.json"), "w") as f:
        json.dump(meta, f, indent=1, sort_keys=True)


if __name__ == "__main__":
    main()
