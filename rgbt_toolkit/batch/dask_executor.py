"""The Dask executor: batch items as tasks on a Dask distributed cluster (optional extra ``rgbt-toolkit[dask]``).

Dask is imported only when this executor is made, with a one-line error naming the extra when it is missing. Each
task runs through :func:`~rgbt_toolkit.batch.executor_base.call_item`, like the local executors, so thread limits,
timing and error capture are the same everywhere.
"""

from __future__ import annotations

import re

from rgbt_toolkit.batch.executor_base import Executor, Outcome, call_item, threads_per_worker
from rgbt_toolkit.errors import InputError, RgbtError

# PROTOCOL://HOST:PORT, HOST a name, an IPv4 address or a bracketed IPv6 address
_ADDRESS = re.compile(r"^(tcp|tls|ws|wss|ucx)://(\[[0-9A-Fa-f:.]+\]|[^\s:/\[\]]+):(\d{1,5})$")


def check_scheduler_address(address: str) -> str:
    """Refuse a malformed ``--scheduler`` in one line (Dask itself answers with a long traceback)."""
    match = _ADDRESS.match(address.strip())
    if match is None or not 0 < int(match[3]) < 65536:
        raise InputError(f"--scheduler: expected tcp://HOST:PORT (e.g. tcp://10.0.0.5:8786), got '{address}'")
    return address.strip()


def _import_distributed():
    try:
        import distributed
    except ImportError:
        raise RgbtError("the Dask executor needs Dask distributed, which is not installed; "
                        "run: pip install 'rgbt-toolkit[dask]'") from None
    return distributed


class DaskExecutor(Executor):
    """Items as tasks on a Dask distributed cluster.

    Parameters
    ----------
    scheduler : str, optional
        Address of a running scheduler, ``tcp://HOST:PORT``. Workers must see the same paths as this machine
        (a shared file system) since items carry paths and tasks write their outputs themselves.
    local_workers : int, optional
        Start a local cluster of this many single-threaded worker processes instead (used when ``scheduler`` is
        None); it is shut down by :meth:`close`.
    threads : int, optional
        torch/OpenCV/BLAS threads inside each task; default: this machine's cores divided by ``local_workers`` for a
        local cluster, 1 for a remote one (Dask's own default for its workers' BLAS).
    """

    name = "dask"

    def __init__(self, scheduler: str | None = None, local_workers: int | None = None,
                 threads: int | None = None) -> None:
        if scheduler is not None:
            scheduler = check_scheduler_address(scheduler)
        distributed = _import_distributed()
        if scheduler is None and local_workers is None:
            raise InputError("the Dask executor needs --scheduler tcp://HOST:PORT or --dask-local N")
        if scheduler is not None and local_workers is not None:
            raise InputError("give either --scheduler or --dask-local, not both")
        self._cluster = None
        if scheduler is not None:
            try:
                self._client = distributed.Client(scheduler, timeout="20s")
            except (OSError, TimeoutError) as exc:
                raise RgbtError(f"cannot reach the Dask scheduler at {scheduler} ({exc}); start it with "
                                f"'dask scheduler' and check the address") from None
            self.workers = len(self._client.scheduler_info().get("workers", {})) or 1
            self.threads = 1 if threads is None else threads
            self.address = scheduler
        else:
            if local_workers < 1:
                raise InputError(f"--dask-local must be at least 1, got {local_workers}")
            # dashboard on any free port, so a second cluster on the machine never clashes with the first
            self._cluster = distributed.LocalCluster(n_workers=local_workers, threads_per_worker=1, processes=True,
                                                     dashboard_address=":0")
            self._client = distributed.Client(self._cluster)
            self.workers = local_workers
            self.threads = threads_per_worker(local_workers) if threads is None else threads
            self.address = self._cluster.scheduler_address

    def describe(self) -> str:
        where = "local cluster" if self._cluster is not None else self.address
        return f"dask ({where}, {self.workers} worker{'s' if self.workers != 1 else ''})"

    def map(self, fn, items):
        from distributed import as_completed

        items = list(items)
        if not items:
            return
        futures = self._client.map(call_item, [fn] * len(items), items, [self.threads] * len(items), pure=False)
        by_key = {future.key: item for future, item in zip(futures, items)}
        try:
            for future in as_completed(futures):
                try:
                    outcome = future.result()
                except Exception as exc:  # the worker holding the task died or the scheduler went away
                    outcome = Outcome(error=f"{type(exc).__name__}: {str(exc).strip()[:200]}")
                yield by_key[future.key], outcome
        finally:
            self._client.cancel([f for f in futures if not f.done()])

    def close(self) -> None:
        self._client.close()
        if self._cluster is not None:
            self._cluster.close()
            self._cluster = None
