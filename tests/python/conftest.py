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


def _assert_releases_gil(call: Callable[[], object], busy_seconds: float = 0.3) -> None:
    """While ``call`` runs in a worker thread, this thread keeps running Python: it could not if the call held the
    GIL. The worker repeats ``call`` until the calls add up to ``busy_seconds`` (one call can be a few milliseconds,
    too short to see on a loaded 2-core machine); asserts at least 3 ticks of this thread inside the middle halves of
    the calls."""
    spans: list[tuple[float, float]] = []

    def work() -> None:
        busy = 0.0
        while busy < busy_seconds and len(spans) < 1000:
            start = time.perf_counter()
            call()
            end = time.perf_counter()
            spans.append((start, end))
            busy += end - start

    worker = threading.Thread(target=work)
    ticks = []
    worker.start()
    while worker.is_alive():
        ticks.append(time.perf_counter())
        time.sleep(0.0005)
    worker.join()
    inside = [t for t in ticks for start, end in spans if start + (end - start) / 4 < t < end - (end - start) / 4]
    assert len(inside) >= 3, (len(spans), sum(e - s for s, e in spans), len(ticks), len(inside))


@pytest.fixture
def assert_releases_gil() -> Callable[[Callable[[], object]], None]:
    return _assert_releases_gil
