"""Names of OGBench's info entries in our infos.

OGBench names them ``proprio/joint_pos``, ``privileged/block_0_pos``, ... Our datasets are HDF5,
where a ``/`` in a column name makes a group: ``proprio/joint_pos`` could not be stored next to
the ``proprio`` column, and grouped columns are not read back. So the envs give these entries
with ``.`` instead (``proprio.joint_pos``), the separator of nested names everywhere else in
stable_worldmodel (``variation.agent.color``, ``pixels.front``); the expert turns them back
into OGBench's names for its oracles.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any

SEP = "."
PREFIXES = ("proprio", "privileged")


def ours(name: str) -> str:
    """``proprio/joint_pos`` -> ``proprio.joint_pos`` (other names unchanged)."""
    return name.replace("/", SEP, 1) if name.startswith(tuple(p + "/" for p in PREFIXES)) else name


def ogbench(name: str) -> str:
    """``proprio.joint_pos`` -> ``proprio/joint_pos`` (other names unchanged)."""
    return name.replace(SEP, "/", 1) if name.startswith(tuple(p + SEP for p in PREFIXES)) else name


def is_ogbench_entry(name: str) -> bool:
    """An entry OGBench computes (``proprio.*`` / ``privileged.*`` in our infos)."""
    return name.startswith(tuple(p + SEP for p in PREFIXES))


def to_ours(info: Mapping[str, Any]) -> dict[str, Any]:
    return {ours(k): v for k, v in info.items()}
