"""Record upstream 0.1.1 TwoRoom-v1 reference numbers (run in the 0.1.1 venv: python record_two_room_v1.py OUT.npz)."""

import sys
import warnings

warnings.filterwarnings("ignore")
import gymnasium as gym
import numpy as np

import stable_worldmodel  # noqa: F401  (registers swm/TwoRoom-v1)

rng = np.random.default_rng(0)
CASES = {
    "default": None,
    "doors": {
        "variation": [
            "agent.position",
            "target.position",
            "door.number",
            "door.size",
            "door.position",
            "agent.radius",
            "agent.speed",
        ]
    },
    "all": {"variation": ["all"]},
    "horizontal": {
        "variation": ["target.position"],
        "variation_values": {"wall.axis": 0, "agent.position": [60.0, 40.0]},
    },
}
out = {}
for case, options in CASES.items():
    for seed in (0, 3):
        name = f"{case}_seed{seed}"
        env = gym.make("swm/TwoRoom-v1", disable_env_checker=True)
        obs, info = env.reset(seed=seed, options=options)
        u = env.unwrapped
        acts = rng.uniform(-1, 1, (30, 2)).astype(np.float32)
        S, T, F = [np.asarray(obs)], [], [np.asarray(env.render())]
        for t, a in enumerate(acts, 1):
            o, r, te, tr, i = env.step(a)
            S.append(np.asarray(o))
            T.append(te)
            if t in (15, 30):
                F.append(np.asarray(env.render()))
        out[name + "/actions"] = acts
        out[name + "/obs"] = np.stack(S)
        out[name + "/terminated"] = np.array(T)
        out[name + "/frames"] = np.stack(F)  # steps 0, 15, 30
        out[name + "/goal"] = np.asarray(u._target_img).transpose(1, 2, 0)
        for key in (
            "agent.radius",
            "agent.speed",
            "wall.axis",
            "wall.thickness",
            "door.number",
            "door.size",
            "door.position",
            "agent.color",
        ):
            g, leaf = key.split(".")
            out[name + "/" + key] = np.asarray(u.variation_space[g][leaf].value)
# fixed start and target: into the wall, then through the default door (y = 49) to the target
env = gym.make("swm/TwoRoom-v1", disable_env_checker=True)
env.reset(seed=0, options={"state": np.float32([60, 150]), "target_state": np.float32([170, 60])})
acts = np.concatenate(
    [
        np.tile([1.0, 0.0], (12, 1)),
        np.tile([0.0, -1.0], (22, 1)),
        np.tile([1.0, 0.0], (14, 1)),
        np.tile([0.3, 0.3], (4, 1)),
    ]
).astype(np.float32)
S, T = [], []
for a in acts:
    o, r, te, tr, i = env.step(a)
    S.append(np.asarray(o))
    T.append(te)
out["route/actions"] = acts
out["route/obs"] = np.stack(S)
out["route/terminated"] = np.array(T)
np.savez_compressed(sys.argv[1], **out)
print(out["route/obs"][[11, 33, 47, -1], :2], out["route/terminated"].nonzero())
