"""Shared test helpers."""

from __future__ import annotations

import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parent.parent
VALIDATION_DATA = REPO.parent / "shared" / "validation-data"


@pytest.fixture
def validation_data() -> pathlib.Path:
    """Folder of the published reference series (../shared/validation-data), or skip."""
    if not VALIDATION_DATA.is_dir():
        pytest.skip(f"reference data folder {VALIDATION_DATA} is not present beside the clone")
    return VALIDATION_DATA


def pytest_configure(config):
    # tests never open a window
    os.environ.setdefault("MPLBACKEND", "Agg")
