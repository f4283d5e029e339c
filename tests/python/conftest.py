"""Shared fixtures: where the sources, the third-party anchors and the `hof` program are.

CTest sets HOF_SOURCE_DIR, HOF_ANCHORS_DIR and HOF_EXECUTABLE (tests/CMakeLists.txt), and
PYTHONPATH to the built package.
"""

import os
import pathlib

import pytest


def _path(variable: str) -> pathlib.Path:
    value = os.environ.get(variable)
    if not value:
        pytest.fail(f"{variable} is not set: run the Python tests through ctest (scripts/test.sh)")
    return pathlib.Path(value)


@pytest.fixture(scope="session")
def source_dir() -> pathlib.Path:
    return _path("HOF_SOURCE_DIR")


@pytest.fixture(scope="session")
def examples(source_dir) -> pathlib.Path:
    return source_dir / "examples"


@pytest.fixture(scope="session")
def anchors() -> pathlib.Path:
    return _path("HOF_ANCHORS_DIR")


@pytest.fixture(scope="session")
def hof_executable() -> pathlib.Path:
    return _path("HOF_EXECUTABLE")
