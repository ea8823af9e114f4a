"""A sharded job on a Dask LocalCluster of 2 worker processes, one of which is killed
(SIGKILL) while it runs a shard: Dask reschedules the shard, the binary resumes what the
killed attempt finished, and `btf finalize` commits the output. Run by
tests/cli/dask_jobs.rs, which compares the output with a single-process run's.

    python3 kill_a_worker.py BTF OUTPUT SHARDS -- COMMAND...

Prints one JSON object: the killed worker's pid, the units done when it was killed, and
every shard's output.
"""

import json
import os
import signal
import sys
import threading
import time

from dask.distributed import Client, LocalCluster

import btf_jobs


def units_done(output: str, index: int, count: int, total: int = 81) -> int:
    """View slots of shard INDEX/COUNT with statistics in OUTPUT.partial (its finished
    slots; the blocks are btf's: floor(i * total / count) ..)."""
    lo, hi = index * total // count, (index + 1) * total // count
    stats = output + ".partial/stats"
    try:
        return sum(1 for n in os.listdir(stats) if n.isdigit() and lo <= int(n) < hi)
    except FileNotFoundError:
        return 0


def running_shard(keys) -> int:
    """The shard index of a task key `btf-shard-I-of-N-…`."""
    return int(str(next(iter(keys))).split("-")[2])


def main() -> int:
    btf, output, shards = sys.argv[1], sys.argv[2], int(sys.argv[3])
    command = sys.argv[5:] if sys.argv[4] == "--" else sys.argv[4:]
    cluster = LocalCluster(
        n_workers=2, threads_per_worker=1, processes=True, dashboard_address=":0"
    )
    client = Client(cluster)
    killed = {}

    def killer():
        deadline = time.time() + 60
        while time.time() < deadline:
            for worker, keys in client.processing().items():
                if not keys:
                    continue
                shard = running_shard(keys)
                if units_done(output, shard, shards) >= 2:
                    pid = client.run(os.getpid, workers=[worker])[worker]
                    os.kill(pid, signal.SIGKILL)
                    killed.update(pid=pid, worker=worker, shard=shard)
                    killed["units_done"] = units_done(output, shard, shards)
                    return
            time.sleep(0.01)

    t = threading.Thread(target=killer, daemon=True)
    t.start()
    try:
        job = btf_jobs.run_sharded(
            client,
            command,
            shards,
            output=output,
            btf=btf,
            env={"BTF_TEST_UNIT_DELAY_MS": "30"},
            retries=3,
        )
    finally:
        t.join(timeout=5)
        client.close()
        cluster.close()
    print(
        json.dumps(
            {
                "killed": killed,
                "shards": [r.stdout for r in job.shards],
                "finalize": job.finalize,
            }
        )
    )
    return 0 if killed.get("pid") else 1


if __name__ == "__main__":
    sys.exit(main())
