"""MapKeysWrapper: renames info keys, so an env's own names reach the pipeline under the expected ones."""

from __future__ import annotations

from collections.abc import Mapping

import gymnasium as gym

from ..errors import ArgumentTypeError, ConfigError, UnknownNameError, did_you_mean


class MapKeysWrapper(gym.Wrapper):
    """Renames info keys after ``reset`` and ``step``: each ``info[src]`` moves to ``info[dst]``.

    For example, with ``add_pixels=False`` an env's pixel observation lands in ``info["observation"]``;
    ``key_map={"observation": "pixels"}`` makes it the ``pixels`` the rest of the pipeline uses (videos,
    goals, datasets). Renames happen one after the other in ``key_map`` order, so a later one sees the
    result of the earlier ones, and a destination key that already exists is overwritten.

    Args:
        env: the env to wrap.
        key_map: source key -> destination key (a dict, or anything ``dict()`` accepts).

    Raises:
        UnknownNameError (a ``KeyError``): at ``reset``/``step``, when a source key is not in info.
    """

    def __init__(self, env: gym.Env, key_map: Mapping[str, str]):
        super().__init__(env)
        try:
            self.key_map = dict(key_map)
        except TypeError as exc:
            raise ArgumentTypeError(
                f"MapKeysWrapper requires key_map to be a mapping of source key -> destination key, such as "
                f"{{'observation': 'pixels'}}, got {key_map!r}"
            ) from exc
        except ValueError as exc:
            raise ConfigError(
                f"MapKeysWrapper requires key_map to be a mapping of source key -> destination key, got {key_map!r}"
            ) from exc

    def _rename(self, info: dict) -> dict:
        info = dict(info)
        for src, dst in self.key_map.items():
            if src not in info:
                raise UnknownNameError(
                    f"MapKeysWrapper: key {src!r} not found in info; present keys: {list(info)}."
                    f"{did_you_mean(src, info)}"
                )
            info[dst] = info.pop(src)
        return info

    def reset(self, *, seed=None, options=None):
        obs, info = self.env.reset(seed=seed, options=options)
        return obs, self._rename(info)

    def step(self, action):
        obs, reward, terminated, truncated, info = self.env.step(action)
        return obs, reward, terminated, truncated, self._rename(info)
