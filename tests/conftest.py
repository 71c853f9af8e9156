"""Shared helpers: random instances whose optimal weights are known (ERRATA conditions)."""

from __future__ import annotations

import os
import selectors
import subprocess
import sys
import time

import numpy as np
import pytest
from hypothesis import settings

import adparm

# Hypothesis profiles. "ci", the default: reproducible (derandomized, which also turns the example
# database off) and sized so that tests/test_fuzz.py adds about 9 s to `pytest` on two cores.
# "fuzz": 10,000 random examples per test, for a dedicated run (several minutes):
#     pytest tests/test_fuzz.py --hypothesis-profile=fuzz
# (hypothesis' pytest plugin loads the profile given by --hypothesis-profile after this file.)
settings.register_profile("ci", derandomize=True, deadline=None, max_examples=300)
settings.register_profile("fuzz", max_examples=10_000, deadline=None)
settings.load_profile("ci")


def random_optimal_config(rng: np.random.Generator) -> adparm.Config:
    """A config satisfying K = -Q12 > 0, Q11 = K alpha1 + alpha1^T K, Q22 = R^-1, Q > 0,
    on a random arm with M(q) > 0 (used both as plant and model)."""
    while True:
        A = rng.normal(size=(2, 2))
        K = A @ A.T + 0.5 * np.eye(2)
        alpha1 = rng.uniform(1.0, 20.0) * np.eye(2) + rng.normal(scale=1.0, size=(2, 2))
        B = rng.normal(size=(2, 2))
        R = B @ B.T + 0.1 * np.eye(2)
        Q = np.block([[K @ alpha1 + alpha1.T @ K, -K], [-K, np.linalg.inv(R)]])
        Q = 0.5 * (Q + Q.T)
        if np.linalg.eigvalsh(Q).min() > 1e-3:
            break
    p2 = rng.uniform(0.3, 3.0)
    p3 = rng.uniform(0.05, 2.0)
    p1 = p2 + p3**2 / p2 + rng.uniform(0.1, 5.0)
    return adparm.paper_config().updated(
        {
            "plant": {
                "p1": p1,
                "p2": p2,
                "p3": p3,
                "g1": rng.uniform(0, 20),
                "g2": rng.uniform(0, 10),
            },
            "cost": {"Q": Q, "R": R},
            "control": {"alpha1": alpha1},
            "task": {"qd": [rng.uniform(-1, 1), 0.0]},
        }
    )


def assert_same_arrays(a: adparm.SimulationResult, b: adparm.SimulationResult) -> None:
    """Every recorded array of two results (those of SimulationResult.to_dict()) bit for bit."""
    for name, value in a.to_dict().items():
        if name not in ("status", "wall_time"):
            np.testing.assert_array_equal(value, getattr(b, name), err_msg=name)


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(20261125)


def read_until(stream, text: bytes, timeout: float) -> bytes:
    """Bytes read from ``stream`` (a subprocess's pipe) until ``text`` appears (or the timeout
    passes)."""
    seen = b""
    deadline = time.monotonic() + timeout
    with selectors.DefaultSelector() as selector:
        selector.register(stream, selectors.EVENT_READ)
        while text not in seen and time.monotonic() < deadline:
            if selector.select(timeout=max(0.0, deadline - time.monotonic())):
                chunk = os.read(stream.fileno(), 4096)
                if not chunk:
                    break
                seen += chunk
    return seen


def signal_reproduce(out, horizon: float, signum: int) -> tuple[int, bytes]:
    """Runs ``adparm reproduce --T horizon --no-figures --out out`` in a child process, sends it
    ``signum`` 0.3 s after its progress bar shows that the simulation has started, and returns its
    exit status and stderr."""
    process = subprocess.Popen(
        [sys.executable, "-m", "adparm", "reproduce", "--T", str(horizon), "--no-figures"]
        + ["--out", str(out)],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        started = read_until(process.stderr, b"simulating", timeout=60.0)
        assert b"simulating" in started, started.decode(errors="replace")
        time.sleep(0.3)
        process.send_signal(signum)
        _, stderr = process.communicate(timeout=60.0)
    finally:
        process.kill()
    return process.returncode, stderr
