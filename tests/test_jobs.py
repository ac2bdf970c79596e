"""The worker pool: results in order, every chunk run once, errors named and re-raised."""

from __future__ import annotations

import threading

import pytest

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
