"""What the machine offers this process: cores, memory, how many worker processes it can run (a leaf module:
imports nothing of flexdigit, but its errors when it refuses)."""

from __future__ import annotations

import os

from flexdigit.errors import ParameterError


def available_cores() -> int:
    """Cores this process may run on (its CPU affinity where the OS tells, else the machine's count)."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


#: Worker processes per available core at most: the work is CPU-bound, so more only queue for the cores and each
#: still holds its memory; a few per core leaves room for a user who oversubscribes on purpose.
WORKERS_PER_CORE = 4


def available_memory_bytes() -> int | None:
    """Memory this process could still take, bytes: the kernel's ``MemAvailable``, or what is left under the
    cgroup's limit (a container, a batch job) when that is less; None where neither is known."""
    found = []
    try:
        with open("/proc/meminfo", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("MemAvailable:"):
                    found.append(int(line.split()[1]) * 1024)
                    break
    except (OSError, ValueError, IndexError):
        pass
    try:
        with open("/sys/fs/cgroup/memory.max", encoding="ascii") as fh:
            limit = fh.read().strip()
        with open("/sys/fs/cgroup/memory.current", encoding="ascii") as fh:
            current = int(fh.read().strip())
        if limit != "max":
            found.append(max(int(limit) - current, 0))
    except (OSError, ValueError):
        pass
    return min(found) if found else None


def worker_limit(per_worker_bytes: float) -> tuple[int, str]:
    """The most worker processes this machine can run at once, and why: :data:`WORKERS_PER_CORE` per available
    core, and no more than its free memory holds at ``per_worker_bytes`` each (at least 1)."""
    cores = available_cores()
    limit, why = WORKERS_PER_CORE * cores, f"{WORKERS_PER_CORE} per core, {cores} core{'s' * (cores != 1)}"
    memory = available_memory_bytes()
    if memory is not None:
        by_memory = max(int(memory // per_worker_bytes), 1)
        why += f"; {memory / 2**30:.1f} GiB of memory free at about {per_worker_bytes / 2**30:.1f} GiB a worker"
        limit = min(limit, by_memory)
    return limit, why


def check_workers(workers: int, what: str, per_worker_bytes: float) -> int:
    """``workers`` if this machine can run that many worker processes (:func:`worker_limit`), else a
    :class:`~flexdigit.errors.ParameterError` saying the limit and why: refused, never silently capped."""
    limit, why = worker_limit(per_worker_bytes)
    if workers > limit:
        raise ParameterError(
            f"{what} {workers} is more than this machine can run at once: at most {limit} ({why}); refused, "
            f"give {limit} or fewer"
        )
    return workers
