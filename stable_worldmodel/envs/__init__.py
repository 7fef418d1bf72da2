"""Environments: the registry, the shared env protocols, and one folder per family.

Importing this package registers the ``swm/...`` ids and imports no environment code.
"""

from __future__ import annotations

from typing import Any

from ._registry import WORLDS, EnvEntry, get_entry, list_envs, load_object, register, register_env

__all__ = ["WORLDS", "EnvEntry", "expert_policy", "get_entry", "list_envs", "register", "register_env"]


def expert_policy(env_id: str, **kwargs: Any):
    """A batched expert policy for ``env_id`` that works with :class:`~stable_worldmodel.World`.

    >>> import stable_worldmodel as swm
    >>> policy = swm.envs.expert_policy("swm/Toy-v0")
    """
    from ..errors import unknown_name

    entry = get_entry(env_id)
    if entry.expert is None:
        with_expert = [e for e in list_envs() if get_entry(e).expert]
        raise unknown_name("environment with an expert", env_id, with_expert)
    return load_object(entry.expert)(env_id=env_id, **kwargs)
