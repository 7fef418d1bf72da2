"""Keep a batched cost model's activations in the C heap between planning iterations.

A CPU plan calls ``get_cost`` on ``B * S`` rows per iteration; for 4 envs x 300 samples a
256-wide MLP allocates and frees megabyte-sized activations on every call. glibc's malloc
returns freed memory at the top of the heap to the OS once it exceeds a trim threshold
(128 KiB in a fresh process, then twice the largest block it has served by ``mmap`` and
freed), so model calls page-fault their activations back in: 2,000 to 17,000 page faults,
5 to 10 ms of a 45 ms CEM plan for 4 envs on 2 cores (env-by-env planning stays below it).

glibc raises both thresholds by itself whenever the process frees an ``mmap``-ed block (see
mallopt(3), ``M_MMAP_THRESHOLD``), as any process that once loads a large batch does.
:func:`raise_trim_threshold` frees one such block of 31 MiB, once per process: freed
memory up to 62 MiB then stays in the heap for the next call. The block is never touched
(no page is mapped in); other C libraries just allocate and free it, and glibc leaves
thresholds alone that the user set (``MALLOC_TRIM_THRESHOLD_``, ``MALLOC_MMAP_THRESHOLD_``).
"""

from __future__ import annotations

import torch

__all__ = ["raise_trim_threshold"]

#: just below glibc's cap on the dynamic mmap threshold (32 MiB on 64-bit)
_BLOCK_BYTES = 31 << 20
_done = False


def raise_trim_threshold() -> None:
    """Allocate and free one untouched 31 MiB CPU block, the first time it is called in the process."""
    global _done
    if not _done:
        _done = True
        block = torch.empty(_BLOCK_BYTES, dtype=torch.uint8)
        del block
