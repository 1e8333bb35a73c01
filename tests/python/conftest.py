"""Shared test set-up: a private lookup-table cache, and the check that a call releases the GIL."""

import threading
import time
from collections.abc import Callable, Iterator

import pytest


@pytest.fixture(autouse=True, scope="session")
def isolated_table_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    mp = pytest.MonkeyPatch()
    mp.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path_factory.mktemp("table-cache")))
    yield
    mp.undo()


def _assert_releases_gil(call: Callable[[], object]) -> None:
    """While ``call`` runs in a worker thread, this thread keeps running Python: it could not if the call held the
    GIL. Asserts at least 3 ticks of this thread inside the middle half of the call."""
    span: list[float] = []

    def work() -> None:
        start = time.perf_counter()
        call()
        span.extend([start, time.perf_counter()])

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.0005)
    worker.join()
    start, end = span
    quarter = (end - start) / 4
    inside = [t for t in ticks if start + quarter < t < end - quarter]
    assert len(inside) >= 3, (end - start, len(ticks), len(inside))


@pytest.fixture
def assert_releases_gil() -> Callable[[Callable[[], object]], None]:
    return _assert_releases_gil
