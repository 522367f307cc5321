"""Shared test settings: deterministic hypothesis runs, real data files fetched or the test skipped, and the figures
a drawing test made closed after it."""

from collections.abc import Callable
from pathlib import Path

import pytest
from hypothesis import settings

from gpo.io import datasets

settings.register_profile("gpo", derandomize=True, max_examples=200, deadline=None, print_blob=True)
settings.load_profile("gpo")


@pytest.fixture
def fetch_or_skip() -> Callable[[str], Path]:
    """`gpo.io.datasets.fetch`, skipping the test, with the reason, when the file cannot be had."""

    def fetch(name: str) -> Path:
        try:
            return datasets.fetch(name)
        except datasets.DatasetUnavailable as error:
            pytest.skip(str(error))

    return fetch


@pytest.fixture
def close_figures():
    """Every matplotlib figure closed after the test; a module that draws takes it for each of its tests with
    ``pytestmark = pytest.mark.usefixtures("close_figures")``."""
    yield
    import matplotlib.pyplot as plt

    plt.close("all")
