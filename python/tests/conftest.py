"""Shared by the package's tests: the command-line program the functions are compared with, and
a scratch directory. ctest runs them with PYTHONPATH at the build's python/ and CANALSIM_CLI at
the build's canalsim (python/CMakeLists.txt)."""

import os
import subprocess

import pytest


@pytest.fixture(scope="session")
def cli():
    program = os.environ.get("CANALSIM_CLI")
    if not program or not os.path.exists(program):
        pytest.skip("CANALSIM_CLI does not name the canalsim program (ctest sets it)")

    def run(*args, check=True):
        result = subprocess.run([program, *map(str, args)], capture_output=True, text=True)
        if check and result.returncode != 0:
            raise AssertionError(f"canalsim {' '.join(map(str, args))} failed: {result.stderr}")
        return result

    return run
