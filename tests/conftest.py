"""Shared test settings: deterministic hypothesis runs and the path to the real calibration files."""

from pathlib import Path

import pytest
from hypothesis import settings

settings.register_profile("gpo", derandomize=True, max_examples=200, deadline=None, print_blob=True)
settings.load_profile("gpo")

REAL_DATA = Path(__file__).resolve().parents[1].parent / "shared" / "real_data"


@pytest.fixture
def real_data() -> Path:
    """``../shared/real_data``; the test is skipped, with the reason, where it is absent."""
    if not REAL_DATA.is_dir():
        pytest.skip(f"real calibration files not found at {REAL_DATA}")
    return REAL_DATA
