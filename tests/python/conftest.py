"""Shared fixtures of the Python module's tests: the C++ reference numbers (tests/python/reference.cpp,
17 digits) and the two models."""
import json
import os
import subprocess

import pytest

import armsim

REL_TOL = 1e-12  # the same C++ computation through pybind11: equal up to printing


def measure_longest_stall(call):
    """Runs call() in a thread while this thread keeps iterating a Python loop; returns (the longest
    stretch between the call's start and end without an iteration of the loop, the call's duration).
    With the GIL released by the call the stretch is a small part of the call; with it held through
    the call, no iteration falls inside it and the stretch is the whole call."""
    import threading
    import time
    done = threading.Event()
    span = {}

    def work():
        span["start"] = time.perf_counter()
        call()
        span["end"] = time.perf_counter()
        done.set()

    ticks = []
    worker = threading.Thread(target=work)
    worker.start()
    while not done.is_set():
        ticks.append(time.perf_counter())
        time.sleep(0)
    worker.join()
    inside = [span["start"]] + [t for t in ticks if span["start"] < t < span["end"]] + [span["end"]]
    return max(b - a for a, b in zip(inside, inside[1:])), span["end"] - span["start"]


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


