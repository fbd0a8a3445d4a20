"""Shared fixtures of the Python package's tests (run by CTest: tests/CMakeLists.txt).

DSREG is the dsreg command of the same build (for comparisons with the command line) and
DSREG_SHARED_DATA_DIR the project's real volumes (tests using them are skipped without them).
"""

import os
import subprocess
from pathlib import Path

import pytest


@pytest.fixture(scope="session")
def cli():
    """Runs `dsreg ARGS...`; returns the completed process (stdout, stderr as text); fails the
    test unless it exits 0."""
    executable = os.environ.get("DSREG")
    if not executable:
        pytest.skip("DSREG (the dsreg command) is not set")

    def run(*args):
        result = subprocess.run([executable, *map(str, args)], capture_output=True, text=True)
        assert result.returncode == 0, result.stderr
        return result

    return run


@pytest.fixture(scope="session")
def shared_data():
    folder = Path(os.environ.get("DSREG_SHARED_DATA_DIR", ""))
    if not folder.is_dir():
        pytest.skip("the shared data folder is not available")
    return folder
