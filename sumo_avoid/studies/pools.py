"""Where a batch's runs execute (a local pool of threads each waiting on one run's process, or a Dask
cluster), and what is left of runs a stopped batch did not record.

Both pools yield ``(spec, outcome)`` as runs finish; closing the generator (an interrupt, or an output
that cannot be written) starts no new run and kills the running ones.
"""
from __future__ import annotations

import concurrent.futures as cf
import pathlib
import shutil

from sumo_avoid.runs.job import RunOutcome
from sumo_avoid.runs.worker import kill_all, run_one


def local_results(specs, root, cfg):
    with cf.ThreadPoolExecutor(max_workers=cfg.workers, thread_name_prefix="sumo-avoid-run") as ex:
        futs = {ex.submit(run_one, s.job(), str(root), cfg.timeout_s, cfg.start): s for s in specs}
        try:
            for fut in cf.as_completed(futs):
                yield futs[fut], fut.result()
        except BaseException:  # Ctrl-C, the generator closed, etc.: no new runs, and the running ones are killed
            for f in futs:
                f.cancel()
            kill_all()
            raise


def dask_results(specs, root, cfg):
    from dask.distributed import Client, as_completed

    with Client(cfg.scheduler, set_as_default=False) as client:
        futs = {client.submit(run_one, s.job(), str(root), cfg.timeout_s, cfg.start, key=f"sumo-avoid-{s.key}",
                              pure=False): s for s in specs}
        for fut in as_completed(list(futs), loop=client.loop):
            try:
                res = fut.result()
            except Exception as e:  # the Dask worker itself died, etc.
                res = RunOutcome("failed", error=f"dask: {type(e).__name__}: {e}".splitlines()[0])
            yield futs[fut], res


def discard_unrecorded(root: pathlib.Path, keys) -> None:
    """Remove the folders of runs that never made it into the ledger (``keys``: their run keys): a
    stopped batch's killed runs and partial folders, so nothing half-written is left beside it."""
    for key in keys:
        shutil.rmtree(root / key[:16], ignore_errors=True)
        for part in (root / ".tmp").glob(f"{key[:16]}-*"):
            shutil.rmtree(part, ignore_errors=True)
