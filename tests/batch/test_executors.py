"""The three executors give identical results; pool workers get their thread share; crashes stay per item."""

from __future__ import annotations

import sys
from pathlib import Path

import pytest
from batch_helpers import count_calls

from rgbt_toolkit.batch.dask_executor import DaskExecutor
from rgbt_toolkit.batch.executors import InProcessExecutor, ProcessPoolExecutor, make_executor, threads_per_worker
from rgbt_toolkit.batch.runner import run_job
from rgbt_toolkit.batch.tasks import plan_track, track_item
from rgbt_toolkit.errors import InputError, RgbtError

TEMPLATE = "batch_helpers:template_tracker,batch_helpers:video_tracker"


@pytest.fixture(scope="module")
def pool():
    with ProcessPoolExecutor(workers=2) as executor:
        yield executor


@pytest.fixture(scope="module")
def dask_cluster():
    pytest.importorskip("distributed", reason="Dask is an optional extra (pip install rgbt-toolkit[dask])")
    with DaskExecutor(local_workers=2) as executor:
        yield executor


def _outputs(folder: Path) -> dict[str, bytes]:
    return {str(p.relative_to(folder)): p.read_bytes() for p in sorted(folder.rglob("*"))
            if p.is_file() and not p.name.startswith(".")}


def _track_all(dataset: Path, out: Path, executor) -> dict[str, bytes]:
    job, found = plan_track(dataset, out, TEMPLATE)
    report = run_job(track_item, job, list(found.items), executor)
    assert report.ok and report.count("done") == 5, executor.describe()
    return _outputs(out)


@pytest.fixture()
def in_process_results(dataset, tmp_path) -> dict[str, bytes]:
    results = _track_all(dataset, tmp_path / "in_process", InProcessExecutor())
    assert sorted(results) == ["seq0.txt", "seq1.txt", "seq2.txt", "seq3.txt", "vid/boxes_rgb.txt"]
    return results


def test_process_pool_gives_the_in_process_results(dataset, tmp_path, pool, in_process_results):
    assert _track_all(dataset, tmp_path / "pool", pool) == in_process_results
    assert all(n == 2 for n in count_calls(dataset).values())  # each item once per executor


def test_dask_cluster_gives_the_in_process_results(dataset, tmp_path, dask_cluster, in_process_results):
    assert _track_all(dataset, tmp_path / "dask", dask_cluster) == in_process_results
    assert all(n == 2 for n in count_calls(dataset).values())


def test_pool_workers_share_the_cores(pool):
    from batch_helpers import thread_report

    reports = [outcome.value for _, outcome in pool.map(thread_report, range(6))]
    expected = threads_per_worker(2)
    assert {r["omp"] for r in reports} == {str(expected)} and {r["rgbt"] for r in reports} == {str(expected)}
    assert {r["cv2"] for r in reports} == {expected}
    assert all(r["blas"] == [expected] for r in reports)
    assert len({r["pid"] for r in reports}) <= 2


def test_threads_per_worker_divides_the_cores():
    assert threads_per_worker(1, cores=8) == 8
    assert threads_per_worker(3, cores=8) == 2
    assert threads_per_worker(16, cores=8) == 1


def test_a_worker_crash_fails_only_its_item(dataset, tmp_path, pool):
    (dataset / "seq3").rename(dataset / "seq3crash")
    job, found = plan_track(dataset, tmp_path / "out", "batch_helpers:crashing_tracker,batch_helpers:video_tracker")
    report = run_job(track_item, job, list(found.items), pool)
    assert [r.key for r in report.failed] == ["seq3crash"]
    assert "BrokenProcessPool" in report.failed[0].error and report.failed[0].attempts == 2
    assert report.count("done") == 4
    assert sorted(p.name for p in (tmp_path / "out").glob("seq*.txt")) == ["seq0.txt", "seq1.txt", "seq2.txt"]
    # the pool is usable again afterwards
    assert [o.ok for _, o in pool.map(abs, [-1, 2])] == [True, True]


def test_errors_come_back_as_outcomes_not_exceptions():
    outcomes = dict(InProcessExecutor().map(int, ["3", "x"]))
    assert outcomes["3"].ok and outcomes["3"].value == 3
    assert outcomes["x"].error == "ValueError: invalid literal for int() with base 10: 'x'"
    assert "Traceback" in outcomes["x"].details


def test_missing_dask_names_the_extra(monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import fails as if not installed
    with pytest.raises(RgbtError, match=r"pip install 'rgbt-toolkit\[dask\]'"):
        DaskExecutor(local_workers=1)


def test_executor_options_are_checked():
    with pytest.raises(InputError, match="--workers must be at least 1"):
        ProcessPoolExecutor(workers=0)
    with pytest.raises(InputError, match="cannot be combined"):
        make_executor(in_process=True, dask_local=2)
    assert isinstance(make_executor(in_process=True), InProcessExecutor)
    assert make_executor(workers=3).describe() == "process pool (3 workers)"


@pytest.mark.parametrize("address", ["foo", "tcp://localhost", "tcp://host:0", "localhost:8786", "tcp://a b:1"])
def test_malformed_scheduler_address_is_a_one_line_error(address):
    with pytest.raises(InputError, match=r"^--scheduler: expected tcp://HOST:PORT"):
        make_executor(scheduler=address)


def test_scheduler_address_reaches_a_running_cluster(dask_cluster):
    with DaskExecutor(scheduler=dask_cluster.address) as remote:
        assert remote.workers == 2 and remote.describe().startswith(f"dask ({dask_cluster.address}")
        outcomes = sorted(o.value for _, o in remote.map(abs, [-3, -1, 2]))
    assert outcomes == [1, 2, 3]
    assert sorted(o.value for _, o in dask_cluster.map(abs, [-5])) == [5]  # the cluster itself stays up


@pytest.mark.filterwarnings("always")
def test_items_on_worker_threads_leave_the_process_warning_filters_alone():
    """warnings.catch_warnings swaps process-wide state: on a thread it could steal another item's warnings."""
    import threading
    import warnings

    from rgbt_toolkit.batch.executors import call_item

    def noisy(item):
        warnings.warn(f"item {item}: frame skipped", RuntimeWarning, stacklevel=1)
        return item

    assert call_item(noisy, 1).warnings == ("item 1: frame skipped",)  # the main thread records them
    before = warnings.showwarning
    outcomes = []
    with warnings.catch_warnings(record=True) as seen:
        warnings.simplefilter("always")
        worker = threading.Thread(target=lambda: outcomes.append(call_item(noisy, 2)))
        worker.start()
        worker.join()
    assert outcomes[0].value == 2 and outcomes[0].warnings == ()
    assert [str(w.message) for w in seen] == ["item 2: frame skipped"]  # shown the usual way instead
    assert warnings.showwarning is before
