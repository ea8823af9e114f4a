"""Run sharded ``btf`` jobs on Dask distributed workers (issue #23).

A ``btf`` job that takes ``--shard I/N`` (``btf relight``, ``btf compress``) is split into
``N`` tasks, one per shard; each task runs the ``btf`` binary on a worker with its shard
argument, into the one output every shard shares (a file system all workers see). The
binary does the hard parts — each shard writes only its own frames or view slots,
atomically, checks that it belongs to the job recorded in the output, and resumes what an
earlier attempt finished — so a task can simply be run again: Dask retries a task that
failed (``retries``) and reschedules one whose worker died. When every shard is done,
``btf finalize OUT`` commits the output. Progress is Dask's own: the dashboard
(``client.dashboard_link``) shows one task per shard.

Nothing here is compiled; the only dependency is ``dask[distributed]``.
"""

from __future__ import annotations

import ctypes
import os
import signal
import subprocess
import sys
from dataclasses import dataclass, field
from typing import Optional, Sequence

__all__ = ["ShardResult", "JobResult", "run_shard", "run_sharded", "finalize"]
__version__ = "0.1.0"


@dataclass
class ShardResult:
    """What one shard's ``btf`` run printed."""

    index: int
    count: int
    stdout: str
    stderr: str


@dataclass
class JobResult:
    """A whole sharded job: every shard's result and what ``btf finalize`` printed."""

    shards: list = field(default_factory=list)
    finalize: Optional[str] = None


def _die_with_parent() -> None:  # pragma: no cover - runs in the child before exec
    """Has Linux kill the ``btf`` child (SIGKILL) when the worker that started it dies,
    so a dead worker never leaves an orphan shard writing beside its retry."""
    if sys.platform.startswith("linux"):
        try:
            libc = ctypes.CDLL("libc.so.6", use_errno=True)
            libc.prctl(1, signal.SIGKILL)  # PR_SET_PDEATHSIG
        except OSError:
            pass


def run_shard(
    command: Sequence[str],
    index: int,
    count: int,
    btf: str = "btf",
    cwd: Optional[str] = None,
    env: Optional[dict] = None,
) -> ShardResult:
    """Runs ``btf COMMAND… --shard INDEX/COUNT`` and returns its output; raises
    ``RuntimeError`` (with the binary's error message) when it fails, which Dask retries."""
    args = [btf, *command, "--shard", f"{index}/{count}"]
    full_env = dict(os.environ)
    full_env.setdefault("BTF_NO_PROGRESS", "1")
    full_env.update(env or {})
    proc = subprocess.run(
        args,
        cwd=cwd,
        env=full_env,
        capture_output=True,
        text=True,
        preexec_fn=_die_with_parent,
    )
    if proc.returncode != 0:
        raise RuntimeError(
            f"shard {index}/{count}: {' '.join(args)} exited with {proc.returncode}:\n"
            f"{proc.stderr.strip()}"
        )
    return ShardResult(index, count, proc.stdout, proc.stderr)


def finalize(output: str, btf: str = "btf", cwd: Optional[str] = None) -> str:
    """Runs ``btf finalize OUTPUT`` (idempotent) and returns what it printed."""
    proc = subprocess.run(
        [btf, "finalize", output], cwd=cwd, capture_output=True, text=True
    )
    if proc.returncode != 0:
        raise RuntimeError(f"btf finalize {output}: {proc.stderr.strip()}")
    return proc.stdout


def run_sharded(
    client,
    command: Sequence[str],
    shards: int,
    output: Optional[str] = None,
    btf: str = "btf",
    cwd: Optional[str] = None,
    env: Optional[dict] = None,
    retries: int = 3,
) -> JobResult:
    """Runs ``btf COMMAND…`` as ``shards`` Dask tasks on ``client``'s cluster, each retried
    up to ``retries`` times, then ``btf finalize OUTPUT`` (on this machine) when
    ``output`` is given. ``cwd`` and the paths in ``command`` must mean the same files on
    every worker (a shared file system). Raises when a shard fails every attempt."""
    if shards < 1:
        raise ValueError("shards must be at least 1")
    futures = [
        client.submit(
            run_shard,
            list(command),
            i,
            shards,
            btf=btf,
            cwd=cwd,
            env=env,
            retries=retries,
            pure=False,
            key=f"btf-shard-{i}-of-{shards}-{os.getpid()}-{id(command)}",
        )
        for i in range(shards)
    ]
    results = client.gather(futures)
    job = JobResult(shards=sorted(results, key=lambda r: r.index))
    if output is not None:
        job.finalize = finalize(output, btf=btf, cwd=cwd)
    return job
