"""The lazy entry points of the ``ALE/<Game>-v5`` ids (:mod:`.registration`).

Each imports ale-py on first use (``DependencyNotInstalled`` with ``pip install
"stable-worldmodel[ale]"`` when it is missing) and returns ale-py's own env, built from the
keywords Gymnasium passes (the id's registered ones and the caller's): ``ale_py.env.AtariEnv``
for ``gym.make``, ``ale_py.vector_env.AtariVectorEnv`` for ``gym.make_vec(...,
vectorization_mode="vector_entry_point")``.
"""

from __future__ import annotations

import warnings
from typing import Any

from ..._optional import require


def _ale_py():
    """``import ale_py``: its registration replaces our lazy ids (warnings of a taken id, which only
    show where our import hook was not installed, are silenced for this import only)."""
    with warnings.catch_warnings():
        warnings.filterwarnings("ignore", message=r".*Overriding environment ALE/")
        return require("ale_py", extra="ale", purpose="the ALE/<Game>-v5 environments")


def make_ale_env(**kwargs: Any):
    """ale-py's ``AtariEnv(**kwargs)``."""
    _ale_py()
    from ale_py.env import AtariEnv

    return AtariEnv(**kwargs)


#: ale-py's AtariEnv metadata, read by ``gym.make`` before the env is built (its render modes)
make_ale_env.metadata = {"render_modes": ["human", "rgb_array"], "render_fps": 30}


def make_ale_vector_env(**kwargs: Any):
    """ale-py's ``AtariVectorEnv(**kwargs)`` (``gym.make_vec`` with ``vectorization_mode="vector_entry_point"``)."""
    _ale_py()
    from ale_py.vector_env import AtariVectorEnv

    return AtariVectorEnv(**kwargs)
