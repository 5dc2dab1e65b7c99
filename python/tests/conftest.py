"""Shared fixtures of the Python tests: the data root and the CLI, as the C++ tests find them."""

import os
import pathlib

import pytest


def data_root() -> pathlib.Path:
    root = os.environ.get("CAIRN_DATA_ROOT") or os.environ.get("CAIRN_DEFAULT_DATA_ROOT") or "../shared/data"
    return pathlib.Path(root)


@pytest.fixture
def data() -> pathlib.Path:
    """The shared data root (CAIRN_DATA_ROOT)."""
    root = data_root()
    if not root.is_dir():
        pytest.fail(f"the data root {root} does not exist: set CAIRN_DATA_ROOT")
    return root


@pytest.fixture
def cli() -> str:
    """The `cairn` executable of the same build (CAIRN_CLI), for side-by-side checks."""
    path = os.environ.get("CAIRN_CLI")
    if not path or not os.path.exists(path):
        pytest.fail("CAIRN_CLI does not name the cairn executable (run the tests through ctest)")
    return path
