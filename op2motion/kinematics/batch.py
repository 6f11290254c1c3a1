"""Run a batched model over large N in cache-sized chunks, on all cores.

NumPy releases the GIL inside its array loops, so chunks of one batch computed on a small thread pool run in
parallel. Small batches (the PSO's swarm of 50) run inline: there the pool would cost more than it saves.
"""

from __future__ import annotations

import functools
import math
import os
from concurrent.futures import ThreadPoolExecutor
from typing import Callable

TARGET_CHUNK = 20_000   # poses per chunk: few large NumPy calls keep the GIL released most of the time
MIN_PARALLEL = 8_000    # below this many poses, one inline call is fastest


@functools.lru_cache(maxsize=1)
def _pool() -> ThreadPoolExecutor:
    return ThreadPoolExecutor(max_workers=max(1, min(4, os.cpu_count() or 1)), thread_name_prefix="op2motion-fk")


def run_chunked(n: int, work: Callable[[int, int], None]) -> None:
    """Call ``work(start, stop)`` over [0, n) in chunks, in parallel when the batch is large."""
    if n < MIN_PARALLEL:
        work(0, n)
        return
    workers = _pool()._max_workers
    chunks = max(workers, workers * math.ceil(n / (TARGET_CHUNK * workers)))
    bounds = [round(i * n / chunks) for i in range(chunks + 1)]
    futures = [_pool().submit(work, a, b) for a, b in zip(bounds[:-1], bounds[1:]) if b > a]
    for f in futures:
        f.result()
