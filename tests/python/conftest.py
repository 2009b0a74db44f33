"""Shared fixtures of the Python module's tests: the C++ reference numbers (tests/python/reference.cpp,
17 digits) and the two models."""
import json
import os
import subprocess

import pytest

import armsim

REL_TOL = 1e-12  # the same C++ computation through pybind11: equal up to printing


@pytest.fixture(scope="session")
def reference():
    out = subprocess.run([os.environ["ARMSIM_REFERENCE"]], check=True, capture_output=True, text=True).stdout
    return json.loads(out)


@pytest.fixture(scope="session")
def thesis():
    return armsim.Model.load("thesis")


@pytest.fixture(scope="session")
def elbow():
    return armsim.Model.load("elbow")


