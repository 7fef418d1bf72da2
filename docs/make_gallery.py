"""Draw every registered environment: its default look and a few sampled variations.

Usage: python docs/make_gallery.py [--out docs/images] [--size 160] [--variations 3]
                                   [--envs ID ...] [--tag TAG] [--skip-tag TAG] [--gallery gallery.png]
Writes one PNG per env (default look first, then ``variation: ["all"]`` samples) and
``--gallery`` with all of them, one row per env. The README's pictures:
``--skip-tag mujoco`` (gallery.png) and ``--tag mujoco --size 128 --gallery gallery_mujoco.png``.
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
    parser.add_argument("--envs", nargs="+", default=None, help="env ids (default: every registered env but Toy)")
    parser.add_argument("--tag", default=None, help="only envs with this tag")
    parser.add_argument("--skip-tag", default=None, help="leave out envs with this tag")
    parser.add_argument("--gallery", default="gallery.png", help="file name of the picture of all rows")
    args = parser.parse_args()
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    env_ids = args.envs or [e for e in swm.envs.list_envs(tag=args.tag) if e != "swm/Toy-v0"]
    if args.skip_tag:
        env_ids = [e for e in env_ids if e not in set(swm.envs.list_envs(tag=args.skip_tag))]
    for env_id in env_ids:
        row = env_row(env_id, args.size, args.variations)
        name = env_id.split("/")[-1]
        Image.fromarray(row).save(out / f"{name}.png")
        label = Image.new("RGB", (row.shape[1], 22), "white")
        ImageDraw.Draw(label).text(
            (4, 4), f"{env_id}: default, then 'variation': ['all'] with seeds 1..{args.variations}", fill="black"
        )
        rows.append(np.concatenate([np.asarray(label), row]))
    Image.fromarray(np.concatenate(rows, axis=0)).save(out / args.gallery)
    print(f"wrote {len(rows)} env pictures and {args.gallery} to {out}")


if __name__ == "__main__":
    main()
