"""``python -m btf_jobs``: run one sharded ``btf`` job on a Dask cluster.

    python -m btf_jobs --shards 8 --workers 4 --output out.eig -- compress m.btf -c 16 -o out.eig
    python -m btf_jobs --scheduler tcp://head:8786 --shards 50 --output frames -- \
        relight scene.toml --env a.exr --rotations 200 -o frames

Without ``--scheduler`` a ``LocalCluster`` of ``--workers`` processes is started. The
dashboard address is printed; it shows one task per shard.
"""

from __future__ import annotations

import argparse
import sys

from . import run_sharded


def main(argv=None) -> int:
    p = argparse.ArgumentParser(prog="btf-jobs", description=__doc__.splitlines()[0])
    p.add_argument("--shards", type=int, required=True, help="number of shards N")
    p.add_argument("--scheduler", help="address of a running Dask scheduler")
    p.add_argument("--workers", type=int, default=2, help="LocalCluster worker processes")
    p.add_argument("--retries", type=int, default=3, help="attempts per shard beyond the first")
    p.add_argument("--output", help="run `btf finalize OUTPUT` when every shard is done")
    p.add_argument("--btf", default="btf", help="path of the btf binary")
    p.add_argument("command", nargs=argparse.REMAINDER, help="-- then the btf command")
    a = p.parse_args(argv)
    command = a.command[1:] if a.command[:1] == ["--"] else a.command
    if not command:
        p.error("give the btf command after --")
    from dask.distributed import Client, LocalCluster

    if a.scheduler:
        client = Client(a.scheduler)
        cluster = None
    else:
        cluster = LocalCluster(n_workers=a.workers, threads_per_worker=1, processes=True)
        client = Client(cluster)
    print(f"dashboard: {client.dashboard_link}", file=sys.stderr)
    try:
        job = run_sharded(
            client, command, a.shards, output=a.output, btf=a.btf, retries=a.retries
        )
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    for r in job.shards:
        sys.stdout.write(r.stdout)
    if job.finalize:
        sys.stdout.write(job.finalize)
    return 0


if __name__ == "__main__":
    sys.exit(main())
