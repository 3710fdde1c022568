"""Shared fixtures of the Python module's tests (python/CMakeLists.txt runs them from ctest, with
PYTHONPATH at the build tree's package and ATMO_CLI at the built `atmo` program)."""

import os
import shutil
import subprocess

import numpy as np
import pytest

import atmo


@pytest.fixture(scope="session")
def earth():
    return atmo.Model("hillaire", preset="earth")


@pytest.fixture(scope="session")
def cli():
    """The built `atmo` program, as a function: cli(args..., stdin=None) -> stdout."""
    path = os.environ.get("ATMO_CLI") or shutil.which("atmo")
    if not path or not os.path.exists(path):
        pytest.fail("set ATMO_CLI to the built atmo program (ctest does)")

    def run(*args, stdin=None):
        result = subprocess.run([path, *args], input=stdin, capture_output=True, text=True)
        if result.returncode != 0:
            raise AssertionError(f"atmo {' '.join(args)} failed: {result.stderr.strip()}")
        return result.stdout

    return run


def parse_csv(text):
    """The rows of a CSV as dicts of floats, by header name."""
    lines = text.strip().splitlines()
    header = lines[0].split(",")
    return [dict(zip(header, map(float, line.split(",")))) for line in lines[1:]]


# `atmo sample` prints %.9e: 10 significant digits. Half a unit in the last printed digit is a
# relative 5e-10; a value printed from the same double agrees to that.
PRINTED_RTOL = 5e-10


def assert_printed(module_value, printed_value):
    np.testing.assert_allclose(module_value, printed_value, rtol=PRINTED_RTOL, atol=1e-300)
