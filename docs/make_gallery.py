"""Draw every registered environment: its default look and a few sampled variations.

Usage: python docs/make_gallery.py [--out docs/images] [--size 160] [--variations 3]
Writes one PNG per env (default look first, then ``variation: ["all"]`` samples) and
``gallery.png`` with all of them, one row per env.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import gymnasium as gym
import numpy as np
from PIL import Image, ImageDraw

import stable_worldmodel as swm


def env_row(env_id: str, size: int, variations: int) -> np.ndarray:
    env = gym.make(env_id, disable_env_checker=True)
    env.unwrapped.set_render_size((size, size))
    frames = []
    for k in range(variations + 1):
        options = None if k == 0 else {"variation": ["all"]}
        env.reset(seed=k, options=options)
        frames.append(env.render())
    env.close()
    pad = np.full((size, 4, 3), 255, np.uint8)
    return np.concatenate([x for f in frames for x in (f, pad)][:-1], axis=1)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", default="docs/images")
    parser.add_argument("--size", type=int, default=160)
    parser.add_argument("--variations", type=int, default=3)
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for env_id in swm.envs.list_envs():
        if env_id == "swm/Toy-v0":
            continue
        row = env_row(env_id, args.size, args.variations)
        name = env_id.split("/")[-1]
        Image.fromarray(row).save(out / f"{name}.png")
        label = Image.new("RGB", (row.shape[1], 22), "white")
        ImageDraw.Draw(label).text((4, 4), f"{env_id}: default, then 'variation': ['all'] with seeds 1..{args.variations}", fill="black")
        rows.append(np.concatenate([np.asarray(label), row]))
    Image.fromarray(np.concatenate(rows, axis=0)).save(out / "gallery.png")
    print(f"wrote {len(rows)} env pictures and gallery.png to {out}")


if __name__ == "__main__":
    main()
