"""Keep lookup tables that tests build out of the user's cache folder."""

from collections.abc import Iterator

import pytest


@pytest.fixture(autouse=True, scope="session")
def isolated_table_cache(tmp_path_factory: pytest.TempPathFactory) -> Iterator[None]:
    mp = pytest.MonkeyPatch()
    mp.setenv("SPECTRAL_SKIN_CACHE_DIR", str(tmp_path_factory.mktemp("table-cache")))
    yield
    mp.undo()
