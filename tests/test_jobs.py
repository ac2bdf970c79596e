"""The worker pool: results in order, every chunk run once, errors named and re-raised."""

from __future__ import annotations

import threading

import numpy as np
import pytest

from ecs_engine import native
from ecs_engine.jobs import JobError, JobPool, over_rows, row_chunks


def test_map_runs_every_chunk_once_in_order_on_several_threads():
    seen = []
    lock = threading.Lock()

    def job(x):
        with lock:
            seen.append((x, threading.get_ident()))
        return x * x

    with JobPool(4) as pool:
        assert pool.map(job, list(range(50))) == [x * x for x in range(50)]
    assert sorted(x for x, _ in seen) == list(range(50))


def test_one_thread_runs_inline():
    main = threading.get_ident()
    with JobPool(1) as pool:
        assert pool.map(lambda _: threading.get_ident(), [1, 2, 3]) == [main] * 3
    with pytest.raises(ValueError):
        JobPool(0)


def test_a_failing_job_names_its_chunk_and_the_pool_still_works():
    def job(x):
        if x == 3:
            raise ValueError("bad chunk")
        return x

    with JobPool(3) as pool:
        with pytest.raises(JobError, match=r"chunk rows 3 failed: ValueError: bad chunk") as info:
            pool.map(job, [0, 1, 2, 3, 4], names=[f"rows {i}" for i in range(5)])
        assert isinstance(info.value.__cause__, ValueError)
        assert pool.map(job, [0, 1, 2]) == [0, 1, 2]  # the next frame runs


def test_row_chunks_and_over_rows_cover_every_row_once():
    assert row_chunks(0, 10) == []
    chunks = row_chunks(25, 10)
    assert [(c.start, c.stop) for c in chunks] == [(0, 10), (10, 20), (20, 25)]
    covered = []
    lock = threading.Lock()

    def job(s):
        with lock:
            covered.extend(range(s.start, s.stop))

    with JobPool(4) as pool:
        over_rows(pool, 100_000, job, chunk_rows=1000)
    assert sorted(covered) == list(range(100_000))


def test_a_map_inside_a_job_runs_inline_instead_of_deadlocking():
    with JobPool(4) as pool:

        def job(x):
            return sum(pool.map(lambda y: x * y, [1, 2, 3]))

        assert pool.map(job, list(range(8))) == [6 * x for x in range(8)]


def test_maps_from_two_threads_at_once_both_complete():
    with JobPool(4) as pool:
        out = {}

        def caller(tag):
            out[tag] = [pool.map(lambda x: (tag, x), list(range(20))) for _ in range(50)][-1]

        threads = [threading.Thread(target=caller, args=(t,)) for t in "ab"]
        for t in threads:
            t.start()
        for t in threads:
            t.join(timeout=30)
        assert out == {t: [(t, x) for x in range(20)] for t in "ab"}


def test_the_lowest_failing_chunk_is_reported_and_close_stops_the_workers():
    def job(x):
        if x in (2, 5):
            raise KeyError(x)
        return x

    pool = JobPool(3)
    with pytest.raises(JobError, match=r"chunk #2 failed"):
        pool.map(job, list(range(8)))
    workers = list(pool._workers)
    pool.close()
    assert workers and not any(w.is_alive() for w in workers)
    assert pool.map(job, [0, 1]) == [0, 1]  # a closed pool still runs, inline


def test_resize_changes_the_thread_count_in_place():
    import threading

    pool = JobPool(2)
    try:
        seen = set()
        barrier = threading.Barrier(4, timeout=5)

        def job(_: int) -> None:
            seen.add(threading.get_ident())
            barrier.wait()  # four chunks only finish if four threads run them at once

        pool.resize(4)
        assert pool.threads == 4
        pool.map(job, list(range(4)))
        assert len(seen) == 4
        pool.resize(1)
        assert pool.threads == 1 and pool.map(lambda x: x * 2, [1, 2, 3]) == [2, 4, 6]
        with pytest.raises(ValueError, match="at least 1"):
            pool.resize(0)
        assert pool.threads == 1
    finally:
        pool.close()


def _take_kernel(counters, out, n):  # pragma: no cover
    for k in range(n):
        out[k] = native.fetch_add(counters, 1, 1)


_take = native.njit(_take_kernel)


@pytest.mark.skipif(_take is None, reason="compiled kernels share counters")
def test_threads_adding_to_a_shared_counter_lose_no_add_and_each_take_their_own_value():
    kernel = _take
    counters, n = np.zeros(2, np.int64), 100_000
    outs = [np.empty(n, np.int64) for _ in range(4)]
    with JobPool(4) as pool:
        pool.map(lambda out: kernel(counters, out, n), outs)
    assert counters[1] == 4 * n and counters[0] == 0
    assert np.array_equal(np.sort(np.concatenate(outs)), np.arange(4 * n))  # no value taken twice
