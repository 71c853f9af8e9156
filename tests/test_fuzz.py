"""Fuzzing with hypothesis: valid configs run cleanly, invalid ones are refused naming the field,
and the C++ core refuses or survives any settings.

The default profile "ci" (tests/conftest.py) runs a fixed, derandomized set of examples; for a
long random search, ``pytest tests/test_fuzz.py --hypothesis-profile=fuzz`` (10,000 per test).
"""

from __future__ import annotations

import dataclasses
import math
from typing import Any

import numpy as np
import pytest
from hypothesis import event, example, given, note
from hypothesis import strategies as st

import adparm
from adparm import _core
from adparm.config import MAX_POINTS, MAX_RECORD_EVERY
from adparm.simulation import core_settings

from conftest import assert_same_arrays

# short learning runs have not converged, and adparm.simulate says so (tests/test_truth.py)
pytestmark = pytest.mark.filterwarnings("ignore::adparm.ApproximationWarning")

SECTIONS = {
    name: [f.name for f in dataclasses.fields(getattr(adparm.Config(), name))]
    for name in (f.name for f in dataclasses.fields(adparm.Config) if not f.name.startswith("_"))
}
ARM_KEYS = ("p1", "p2", "p3", "g1", "g2", "coulomb", "viscous")
MAX_STEPS = 3000  # RK4 steps per simulated example: keeps the default suite fast


# --- strategies of valid plain dicts ------------------------------------------------------------


# True about once in five draws (hypothesis favours the first of sampled_from's values)
rarely = st.sampled_from([False, False, False, False, True])


def reals(low: float, high: float) -> st.SearchStrategy[float]:
    return st.floats(low, high, allow_nan=False, allow_infinity=False)


def vectors(n: int, low: float, high: float) -> st.SearchStrategy[list[float]]:
    return st.lists(reals(low, high), min_size=n, max_size=n)


def matrices(rows: int, cols: int, low: float, high: float) -> st.SearchStrategy[list]:
    return st.lists(vectors(cols, low, high), min_size=rows, max_size=rows)


@st.composite
def spd_matrices(draw: st.DrawFn, n: int, floor: float) -> list[list[float]]:
    """L L^T + c I with c >= floor, exactly symmetric."""
    lower = np.array(draw(matrices(n, n, -3.0, 3.0)))
    matrix = lower @ lower.T + draw(reals(floor, 5.0)) * np.eye(n)
    return (0.5 * (matrix + matrix.T)).tolist()


@st.composite
def hurwitz_gains(draw: st.DrawFn) -> list[list[float]]:
    """s I + N with s > ||N||_F: every eigenvalue s + lambda(N) has a positive real part."""
    n = np.array(draw(matrices(2, 2, -10.0, 10.0)))
    s = float(np.linalg.norm(n)) + draw(reals(0.1, 20.0))
    return (s * np.eye(2) + n).tolist()


@st.composite
def arms(draw: st.DrawFn) -> dict[str, float]:
    """p1, p2, p3 with M(q) > 0 (det margin >= 0.01), and the other arm constants."""
    p2 = draw(reals(0.2, 5.0))
    p3 = draw(reals(-3.0, 3.0))
    arm = {"p1": p2 + p3 * p3 / p2 + draw(reals(0.05, 10.0)), "p2": p2, "p3": p3}
    arm.update(g1=draw(reals(-20.0, 20.0)), g2=draw(reals(-20.0, 20.0)))
    arm.update(coulomb=draw(reals(-1.0, 1.0)), viscous=draw(reals(-0.5, 2.0)))
    return arm


def some(draw: st.DrawFn, values: dict[str, Any]) -> dict[str, Any]:
    """A random subset of the keys: the others take their defaults."""
    return {key: value for key, value in values.items() if draw(st.booleans())}


@st.composite
def trajectories(draw: st.DrawFn, T: float) -> Any:
    kind = draw(st.sampled_from(["set-point", "sinusoid", "samples"]))
    if kind == "set-point":
        return draw(vectors(2, -1.5, 1.5))
    if kind == "sinusoid":
        n = draw(st.integers(1, 3))
        pair = n == 1 and draw(st.booleans())

        def table(low: float, high: float) -> Any:
            return draw(vectors(2, low, high) if pair else matrices(2, n, low, high))

        qd = {"kind": "sinusoid", "amplitude": table(-1.0, 1.0), "frequency": table(0.0, 5.0)}
        if draw(st.booleans()):
            qd["phase"] = table(0.0, 2 * math.pi)
        if draw(st.booleans()):
            qd["offset"] = draw(vectors(2, -1.0, 1.0))
        return qd
    # samples at least 10 ms apart: closer ones with other values make the spline overflow,
    # which config refuses
    first = -draw(reals(0.0, 1.0))
    last = T + draw(reals(0.0, 1.0))
    inner = {round(v, 2) for v in draw(st.lists(reals(0.0, T), max_size=6))}
    t = [first, *sorted(v for v in inner if first + 0.01 <= v <= last - 0.01), last]
    q = draw(matrices(len(t), 2, -1.5, 1.5))
    qd = {"kind": "samples", "t": t, "q": q}
    if draw(st.booleans()):
        qd["boundary"] = draw(st.sampled_from(["not-a-knot", "clamped", "natural"]))
    return qd


@st.composite
def probes(draw: st.DrawFn, T: float) -> dict[str, Any]:
    n = draw(st.integers(0, 5))
    probe = {
        "frequencies": draw(vectors(n, 0.0, 20.0)),
        "amplitude": draw(
            st.one_of(reals(-100.0, 100.0), vectors(2, -100.0, 100.0), matrices(2, n, -100, 100))
        ),
        "until": draw(reals(0.0, 2 * T)),
        "ramp": draw(reals(0.0, 2.0)),
    }
    if draw(st.booleans()):
        probe["phases"] = draw(st.none() | matrices(2, n, 0.0, 2 * math.pi))
    if draw(rarely):  # sometimes the defaults (which need 4 frequencies)
        probe = {key: probe[key] for key in ("until", "ramp") if draw(st.booleans())}
    return probe


@st.composite
def extrapolations(draw: st.DrawFn) -> dict[str, Any]:
    mode = draw(st.sampled_from(["off", "fixed", "local", "grid"]))
    if mode == "off":
        return draw(st.sampled_from([{}, {"points": 0}]))
    points = draw(st.sampled_from([1, 16])) if mode == "grid" else draw(st.integers(0, 5))
    box = draw(reals(0.01, 3.0) | vectors(4, 0.01, 3.0))
    return {"points": points, "mode": mode, "box": box, "seed": draw(st.integers(0, 2**32 - 1))}


@st.composite
def valid_dicts(draw: st.DrawFn) -> dict[str, dict[str, Any]]:
    """A plain dict over every section, with short horizons (at most MAX_STEPS steps)."""
    dt = draw(reals(1e-4, 5e-3))
    T = dt * draw(reals(1.0, MAX_STEPS))
    sim = {"T": T, "dt": dt}
    sim.update(
        some(
            draw,
            {
                "record_every": draw(st.integers(1, 50) | st.just(MAX_RECORD_EVERY)),
                "divergence_bound": draw(
                    reals(1.0, 1e8) | st.sampled_from([1e300, np.finfo(float).max])
                ),
            },
        )
    )
    kind = draw(st.sampled_from(["adp", "rise", "pd", "optimal"]))
    gain = reals(0.0, 200.0) | matrices(2, 2, -50.0, 200.0)
    controller = {
        "kind": kind,
        "basis": draw(st.sampled_from(["augmented", "paper", "structured"])),
        "rise": True if kind == "rise" else draw(st.booleans()),
        "kp": draw(gain),
        "kd": draw(gain),
    }

    def arm_keys(arm: dict[str, float]) -> dict[str, float]:
        """Some keys of arm, with p1, p2, p3 all or none (M > 0 needs them together)."""
        chosen = some(draw, arm)
        mass = ("p1", "p2", "p3")
        together = draw(st.booleans())
        return {
            key: arm[key] if key in mass and together else chosen[key]
            for key in arm
            if (key in mass and together) or (key not in mass and key in chosen)
        }

    size = 6 if controller["basis"] == "structured" else 8
    weights = st.just([0.0] * size) | vectors(size, -10.0, 10.0)
    sections = {
        "plant": {**arm_keys(draw(arms())), "disturbance": draw(vectors(2, -2.0, 2.0))},
        "model": arm_keys(draw(arms())),
        "task": {
            "q0": draw(vectors(2, -2.0, 2.0)),
            "dq0": draw(vectors(2, -2.0, 2.0)),
            "qd": draw(trajectories(T)),
        },
        "cost": {"Q": draw(spd_matrices(4, 0.01)), "R": draw(spd_matrices(2, 0.05))},
        "control": {
            "alpha1": draw(hurwitz_gains()),
            "ks": draw(reals(0.0, 50.0)),
            "alpha2": draw(reals(0.0, 5.0)),
            "beta1": draw(reals(0.0, 5.0)),
        },
        "critic": {
            "eta_c": draw(reals(0.0, 2000.0)),
            "nu": draw(reals(0.0, 5.0)),
            "gamma0": draw(reals(0.1, 1000.0)),
            "epsilon_T": draw(st.none() | reals(0.0, 0.05)),
        },
        "actor": {
            "eta_a1": draw(reals(0.0, 1.0)),
            "eta_a2": draw(reals(0.0, 5.0)),
            "weight_bound": draw(reals(0.1, 200.0)),
            "positive_e2": draw(st.booleans()),
            "e2_margin": draw(reals(0.0, 1.0)),
        },
        "init": {"critic_weights": draw(weights), "actor_weights": draw(weights)},
        "probe": draw(probes(T)),
        "controller": controller,
        "extrapolation": draw(extrapolations()),
    }
    data = {
        name: values if name in ("plant", "model", "probe") else some(draw, values)
        for name, values in sections.items()
        if draw(st.booleans())
    }
    if "qd" in data.get("task", {}) and isinstance(data["task"]["qd"], dict):
        data["task"]["qd"] = sections["task"]["qd"]  # whole tables only
    if "init" in data:  # weights of the basis' size: keep the basis with them
        data.setdefault("controller", {})["basis"] = controller["basis"]
    if data.get("controller", {}).get("kind") == "rise":
        data["controller"].pop("rise", None)  # rise = False is invalid with kind rise
    data["sim"] = sim  # always: the default 150 s would be 150,000 steps
    return data


# --- running ----------------------------------------------------------------------------------


def assert_finite_result(result: adparm.SimulationResult) -> None:
    for name, value in result.to_dict().items():
        if name not in ("status", "wall_time"):
            assert np.all(np.isfinite(value)), f"{name} holds {value[~np.isfinite(value)][:5]}"


def run_cleanly(config: adparm.Config) -> tuple[adparm.SimulationResult, float | None]:
    """simulate(config): a finished run with finite arrays, or SimulationDiverged whose partial
    result is finite and ends no later than the divergence time. Returns (result, that time).
    A step beyond RK4's limit for the loop's fast rates is refused before the run: (None, None)."""
    try:
        result = adparm.simulate(config)
    except ValueError as error:
        assert str(error).startswith("sim.dt: ") and "too coarse" in str(error), str(error)
        event("refused: step too coarse")
        return None, None
    except adparm.SimulationDiverged as error:
        result = error.result
        assert result.status == "diverged"
        assert 0.0 <= error.time <= config.sim.T * (1 + 1e-12), error.time
        assert np.all(result.t <= error.time)
        assert_finite_result(result)
        event("diverged")
        return result, error.time
    assert result.status == "finished"
    assert result.t.size >= 2 and result.t[0] == 0.0
    assert result.t[-1] == pytest.approx(config.sim.T, rel=1e-12)
    assert_finite_result(result)
    event("finished")
    return result, None


@given(data=valid_dicts())
# found by this test: with a step too large for the critic and a huge divergence bound, the HJB
# error overflowed (NaN) in the last row while the state was still finite
@example(data={"sim": {"T": 0.0911843, "dt": 0.0035070897, "divergence_bound": 1e300}})
# a torque that overflows at t = 0: the run diverges there, with no row
@example(data={"plant": {"g1": 1e308, "g2": 1e308}, "sim": {"T": 0.01}})
def test_valid_configs_run_cleanly_and_reproducibly(data) -> None:
    config = adparm.Config.from_dict(data)
    first, time = run_cleanly(config)
    second, again = run_cleanly(config)
    assert again == time
    if first is None or second is None:  # refused before the run, both times
        assert first is second is None
        return
    assert first.status == second.status
    assert_same_arrays(first, second)


def test_outputs_overflowing_at_t0_diverge_there_without_rows() -> None:
    config = adparm.paper_config().updated({"plant": {"g1": 1e308, "g2": 1e308}})
    run = _core.Simulation(core_settings(config))  # the torque at t = 0 is infinite
    assert (run.status, run.step, run.divergence_time) == ("diverged", 0, 0.0)
    assert run.recording()["t"].size == 0 and np.all(np.isfinite(run.state))


@pytest.mark.parametrize("record_every", [1, 3, 10])
def test_a_row_with_overflowing_outputs_ends_the_run_the_same_in_chunks(record_every) -> None:
    # the HJB error overflows while the state is finite (found by the valid-config fuzzing)
    sim = {"T": 0.2, "dt": 0.0035070897, "divergence_bound": 1e300, "record_every": record_every}
    config = adparm.paper_config().updated({"sim": sim})
    whole = _core.Simulation(core_settings(config))
    whole.advance(whole.steps)
    chunked = _core.Simulation(core_settings(config))
    while chunked.status == "running":
        chunked.advance(1)
    assert whole.status == chunked.status == "diverged"
    assert whole.divergence_time == chunked.divergence_time < config.sim.T
    # record_every = 1: the row due at t = 0.0877 s has a NaN HJB error, so the run stops there;
    # otherwise the state overflows in the next step, and that row (not due) is left out
    assert whole.step == chunked.step
    assert whole.step * config.sim.dt == pytest.approx(whole.divergence_time, rel=1e-12)
    np.testing.assert_array_equal(whole.state, chunked.state)
    a, b = whole.recording(), chunked.recording()
    for name in a:
        np.testing.assert_array_equal(a[name], b[name], err_msg=name)
        assert np.all(np.isfinite(a[name])), name
    assert a["t"][-1] <= whole.divergence_time


# --- invalid configs: one mutation known to be invalid for its field --------------------------

NAN, INF = float("nan"), float("inf")
HUGE = 10**400  # an int beyond the float range
# values that are no number at all (for a field where None means "default", None is left out)
NOT_A_NUMBER = ["1.0", b"1", True, False, {"a": 1.0}, [1.0], [[1.0]], 1j]
NON_FINITE = [NAN, INF, -INF, HUGE, -HUGE]
NEGATIVE = [-1.0, -1e300, -5e-324, -1]
# one bad element in an otherwise numeric array
BAD_ELEMENTS = ["1", True, None, NAN, INF, 1j, HUGE, [1.0], {"a": 1}]


def scalar_cases(kind: str, nullable: bool = False) -> list[Any]:
    cases = NOT_A_NUMBER + NON_FINITE + ([] if nullable else [None])
    if kind in ("nonneg", "pos"):
        cases += NEGATIVE
    if kind == "pos":
        cases += [0.0, -0.0, 0]
    if kind == "above_minus_one":  # control.ks: the gain ks + 1 > 0
        cases += [-1.0, -1, -1.5, -1e300]
    return cases


def with_bad_element(array: Any, element: Any) -> Any:
    array = np.array(array, dtype=object)
    flat = array.reshape(-1)
    if flat.size == 0:
        return [element]
    flat[flat.size // 2] = element
    return array.tolist()


def array_cases(shape: tuple[int, ...], valid: Any) -> list[Any]:
    """Wrong type, wrong shape and bad elements for an array field of fixed ``shape``."""
    ones = np.ones(shape)
    cases = ["1.0", b"1", True, None, {"a": 1.0}, np.ones(shape, dtype=bool), ones + 1j]
    cases += [np.ones((*shape, 1)).tolist(), np.ones(shape[:-1] + (shape[-1] + 1,)).tolist()]
    if len(shape) == 1:
        cases += [1.0, np.ones(shape[0] - 1).tolist()]
    else:
        cases += [1.0, [1.0, 1.0], np.ones((shape[0] + 1, shape[1])).tolist()]
    cases += [with_bad_element(valid, element) for element in BAD_ELEMENTS]
    return cases


def default(section: str, key: str) -> Any:
    return getattr(getattr(adparm.Config(), section), key)


def field_cases(data: dict, section: str, key: str) -> list[Any]:
    """Values known to be invalid for section.key, given the rest of ``data``."""
    values = data.get(section, {})
    value = values.get(key, default(section, key))
    if section == "identifier":
        if key in ("enabled", "gradient_term", "inertia", "gravity", "friction", "stop_probe"):
            return ["true", 1, 0, 1.0, None, [True]]
        if key == "history_size":
            return [0, -1, 100001, 10**30, 2.5, "3", None, True]
        return scalar_cases("pos" if key in ("gain", "window", "max_uncertainty") else "nonneg")
    if key == "e2_cost":  # "logcosh" needs cost.input_bound
        return ["quadraticx", "", "QUADRATIC", 1, None, True, ["quadratic"], "logcosh"]
    if key == "anti_windup":
        return ["true", 1, 0, 1.0, None, [True]]
    if key == "input_bound":  # "auto" needs a limited joint (the two-link arm has none)
        return ["x", "Auto", "auto", -1.0, 0.0, NAN, INF, True, [1.0, 2.0, 3.0], [1.0, -1.0]]
    if key == "torque_limits":  # a model has none of its own
        if section == "model":
            return [[1.0, 1.0], 1.0]
        return ["x", -1.0, 0.0, NAN, True, [1.0, 2.0, 3.0], [1.0, -1.0], [[1.0, 1.0]]]
    if section == "model" and key == "scale":  # in [0.1, 10]
        return [*scalar_cases("pos", nullable=True), 0.05, 10.5, 1e300, "1"]
    if section in ("plant", "model") and key in ARM_KEYS:
        cases = scalar_cases("pos" if key == "p2" else "real", nullable=section == "model")
        if key == "p1":
            cases += [0.0, -1.0]  # det M = p1 p2 - p2^2 - p3^2 < 0
        if key == "p3":
            cases += [1e3]
        return cases
    if key in ("disturbance", "q0", "dq0"):
        return array_cases((2,), value)
    if key in ("critic_weights", "actor_weights"):  # None (left out) is the basis' default
        size = 6 if data.get("controller", {}).get("basis") == "structured" else 8
        valid = [1.0] * size if value is None else value
        return [case for case in array_cases((size,), valid) if case is not None]
    if key in ("Q", "R"):
        n = 4 if key == "Q" else 2
        matrix = np.array(value, dtype=float)
        asymmetric = matrix.copy()
        asymmetric[0, 1] += 0.1 * np.abs(matrix).max()
        flipped = np.eye(n)
        flipped[0, 0] = -1.0
        return array_cases((n, n), value) + [
            asymmetric.tolist(),
            (-matrix).tolist(),
            np.zeros((n, n)).tolist(),
            flipped.tolist(),
        ]
    if key == "alpha1":
        return array_cases((2, 2), value) + [
            (-np.array(value)).tolist(),
            [[0.0, 0.0], [0.0, 0.0]],
            [[1.0, 0.0], [0.0, -1.0]],
            [[0.0, 1.0], [-1.0, 0.0]],  # eigenvalues +-i: real part 0
        ]
    if key in ("kp", "kd"):
        return ["1", None, True, NAN, INF, HUGE, [1.0, 2.0], [[1.0, 2.0, 3.0]] * 2] + [
            with_bad_element([[1.0, 0.0], [0.0, 1.0]], element) for element in BAD_ELEMENTS
        ]
    if key == "urdf":
        return [1, True, "", "/nonexistent/arm.urdf", "bad\0path", ["arm.urdf"]]
    if key == "locked_joints":  # a URDF arm's: refused with the two-link arm too
        return [1, True, "a", [0.0], {"a": 0.0}, {"a": NAN}, {"": 0.0}, {"a": "0"}]
    if key == "gravity":  # gravity is a URDF arm's: refused with the two-link arm too
        return ["1", True, [0.0, 0.0], [0.0, 0.0, NAN], [0.0, 0.0, -9.81]]
    if key == "basis":  # a list of one built-in name is a valid (expression) basis
        return [str(value) + "x", "", str(value).upper(), 1, None, True, [str(value) + "x"], []]
    if key == "degree":  # only with the polynomial basis, and even
        return [2, 4, "2", 3, -2, True, 1.5]
    if key in ("kind", "mode", "boundary"):
        return [str(value) + "x", "", str(value).upper(), 1, None, True, [value]]
    if key in ("rise", "positive_e2"):
        return ["true", 1, 0, 1.0, None, [True]]
    if key == "points":
        return [-1, MAX_POINTS + 1, 10**30, 2.0, 1.5, "3", True, None, NAN]
    if key == "seed":
        return [-1, 2**32, 10**30, 1.0, "0", None, True]
    if key == "record_every":
        return [0, -1, MAX_RECORD_EVERY + 1, HUGE, 2.5, 10.0, "1", None, True]
    if key == "box":
        return [0.0, -1.0, NAN, INF, "1", None, True, [1.0, 1.0], [1.0, 1.0, 0.0, 1.0]] + [
            with_bad_element([1.0] * 4, element) for element in BAD_ELEMENTS
        ]
    if key == "centre":  # any finite number, or one per state
        return [NAN, INF, "1", None, True, [1.0, 1.0], HUGE] + [
            with_bad_element([0.0] * 4, element) for element in BAD_ELEMENTS
        ]
    if key == "frequencies":
        return ["1", None, True, 1.0, [[1.0, 2.0]], {"a": 1}] + [
            with_bad_element([1.0, 2.0], element) for element in BAD_ELEMENTS
        ]
    if key == "amplitude":  # a number, a pair or 2 x n
        return ["1", None, True, NAN, INF, [1.0, 2.0, 3.0], [[1.0]] * 3] + [
            with_bad_element([1.0, 2.0], element) for element in BAD_ELEMENTS
        ]
    if key == "phases":
        n = len(values.get("frequencies", default("probe", "frequencies")))
        return ["1", True, 1.0, np.zeros((3, n)).tolist(), np.zeros((2, n + 1)).tolist()] + [
            with_bad_element(np.zeros((2, max(n, 1))).tolist(), element) for element in BAD_ELEMENTS
        ]
    if key == "epsilon_T":
        return scalar_cases("nonneg", nullable=True) + [2000.0]  # >= gamma0 (at most 1000)
    if key == "T":
        dt = data["sim"]["dt"]
        return scalar_cases("pos") + [dt / 2]  # T < dt
    if key == "tolerance":
        return scalar_cases("pos") + [1.0, 2.0]  # 0 < tolerance < 1
    if key == "dt":
        T = data["sim"]["T"]
        return scalar_cases("pos") + [2 * T, T * 1e-11]  # dt > T; more than 1e10 steps
    kinds = {
        "ks": "above_minus_one",
        "alpha2": "nonneg",
        "beta1": "nonneg",
        "eta_c": "nonneg",
        "nu": "nonneg",
        "gamma0": "pos",
        "eta_a1": "nonneg",
        "eta_a2": "nonneg",
        "weight_bound": "pos",
        "e2_margin": "nonneg",
        "until": "nonneg",
        "ramp": "nonneg",
        "divergence_bound": "pos",
    }
    return scalar_cases(kinds[key])


QD_TABLE_CASES: dict[str, list[Any]] = {
    "amplitude": ["1", None, [[1.0, 2.0]] * 3, with_bad_element([0.5, 0.5], "1")],
    "frequency": [NAN, [[1.0] * 5] * 2, with_bad_element([1.0, 1.0], True)],
    "phase": ["0", [[0.0] * 5] * 2, with_bad_element([0.0, 0.0], INF)],
    "offset": [[0.0], [0.0, 0.0, 0.0], "0", with_bad_element([0.0, 0.0], None)],
    "t": [[0.0, 1e9, 1e9], [0.5, 1e9], [0.0], "0", with_bad_element([0.0, 1e9], NAN)],
    "q": [[[0.0, 0.0]], "0", [[0.0, 0.0, 0.0]] * 2],
    "boundary": ["clamp", 1, None],
    "file": [1, True, "/nonexistent/qd.csv", "bad\0path"],
}


@st.composite
def invalid_mutations(draw: st.DrawFn) -> tuple[dict, tuple[str, ...]]:
    """A valid dict with one invalid change, and the names one of which the error must hold."""
    data = draw(valid_dicts())
    what = draw(st.sampled_from(["field", "field", "field", "qd", "key", "section", "name type"]))
    if what == "name type":  # a section or key name that is no string
        name = draw(st.sampled_from([1, None, 2.5, ("sim",), True]))
        if draw(st.booleans()):
            data[name] = {}
            return data, ("config: section names must be strings",)
        section = draw(st.sampled_from(sorted(SECTIONS)))
        data.setdefault(section, {})[name] = 1.0
        return data, (f"[{section}]: key names must be strings",)
    if what == "section":
        name = draw(
            st.sampled_from(["plantx", "Plant", "critc", "sims", "simulation", ""])
            | st.text(max_size=12).filter(lambda s: s not in SECTIONS)
        )
        data[name] = {}
        return data, (f"[{name}]",)
    section = draw(st.sampled_from(sorted(SECTIONS)))
    if what == "key":
        key = draw(st.sampled_from(SECTIONS[section]))
        bad = draw(
            st.sampled_from([key + "x", "_" + key, key[:-1], key.upper()]).filter(
                lambda k: k not in SECTIONS[section]
            )
        )
        data.setdefault(section, {})[bad] = 1.0
        return data, (f"{section}.{bad}",)
    if what == "qd":
        task = data.setdefault("task", {})
        qd = task.get("qd", [0.0, 0.0])
        if not isinstance(qd, dict):
            task["qd"] = draw(
                st.sampled_from(array_cases((2,), qd) + [{"amplitude": [1, 1]}, {"kind": "sine"}])
            )
            return data, ("task.qd",)
        keys = [
            key
            for key in QD_TABLE_CASES
            if (key in ("t", "q", "boundary", "file")) == (qd["kind"] == "samples")
        ]
        key = draw(st.sampled_from([*keys, "misspelled", "kind"]))
        if key == "misspelled":
            task["qd"] = {**qd, "amplitud": 1.0}
            return data, ("task.qd.amplitud",)
        if key == "kind":
            task["qd"] = {**qd, "kind": draw(st.sampled_from(["sine", "", 1, None]))}
            return data, ("task.qd.kind",)
        if key == "file":
            task["qd"] = {"kind": "samples", "file": draw(st.sampled_from(QD_TABLE_CASES[key]))}
        else:
            task["qd"] = {**qd, key: draw(st.sampled_from(QD_TABLE_CASES[key]))}
        return data, (f"task.qd.{key}",)
    key = draw(st.sampled_from([k for k in SECTIONS[section] if k != "qd"]))
    if key == "points" and draw(st.booleans()):
        data.setdefault(section, {}).update(points=draw(st.sampled_from([2, 5, 15, 17])))
        data[section]["mode"] = "grid"  # needs m^4 points
    else:
        data.setdefault(section, {})[key] = draw(st.sampled_from(field_cases(data, section, key)))
    return data, (f"{section}.{key}",)


@given(case=invalid_mutations())
def test_invalid_configs_are_refused_naming_the_field(case) -> None:
    data, names = case
    with pytest.raises((ValueError, TypeError)) as caught:
        adparm.Config.from_dict(data)
    message = str(caught.value)
    note(message)
    assert any(name in message for name in names), (names, message)


# --- arbitrary JSON-like garbage: refused cleanly, or a config that runs cleanly ----------------


def containers(children: st.SearchStrategy) -> st.SearchStrategy:
    keys = st.text(max_size=6) | st.sampled_from(["kind", "t", "q"])
    return st.lists(children, max_size=5) | st.dictionaries(keys, children, max_size=4)


json_like = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats()
    | st.text(max_size=8)
    | st.sampled_from(["adp", "grid", "samples", "sinusoid", "paper"]),
    containers,
    max_leaves=12,
)
# validated now, not at the first draw: hypothesis reads containers' source to check that it
# recurses, and a file edited during a long fuzzing run would give it the wrong lines
json_like.validate()
# numbers and arrays of numbers, which a field accepts more often than the above
numeric = st.one_of(
    st.floats(),
    st.floats(-1e3, 1e3),
    st.integers(),
    st.integers(0, 20),
    st.lists(st.floats(-1e3, 1e3), max_size=9),
    st.lists(st.lists(st.floats(), min_size=2, max_size=2), min_size=1, max_size=5),
    st.lists(st.lists(st.floats(-1e3, 1e3), min_size=4, max_size=4), min_size=2, max_size=4),
)


@st.composite
def garbage_dicts(draw: st.DrawFn) -> dict:
    data = draw(valid_dicts())
    for _ in range(draw(st.integers(1, 2))):
        # mostly known sections and keys (unknown ones are refused whatever the value)
        section = draw(st.text() if draw(rarely) else st.sampled_from(sorted(SECTIONS)))
        value = draw(json_like if draw(rarely) else numeric)
        if draw(rarely):  # a whole section
            data[section] = value
            continue
        keys = SECTIONS.get(section, [])
        key = draw(st.sampled_from(keys) if keys and not draw(rarely) else st.text())
        if not isinstance(data.get(section), dict):
            data[section] = {}
        data[section][key] = value
    return data


def shortened(config: adparm.Config) -> adparm.Config | None:
    """config with at most MAX_STEPS steps, or None if a step would be too slow to fuzz."""
    if config.extrapolation.points > 64:
        return None
    steps = config.sim.T / config.sim.dt
    return (
        config if steps <= MAX_STEPS else config.updated({"sim": {"T": MAX_STEPS * config.sim.dt}})
    )


@given(data=garbage_dicts())
def test_garbage_is_refused_cleanly_or_runs_cleanly(data) -> None:
    try:
        config = adparm.Config.from_dict(data)
    except (ValueError, TypeError) as error:
        note(str(error))
        event(f"refused: {type(error).__name__}")
        return
    event("accepted")
    config = shortened(config)
    if config is not None:
        run_cleanly(config)


# --- the C++ core on its own: settings built directly, fields overwritten ---------------------

floats_any = st.floats() | st.sampled_from([0.0, -0.0, -1.0, 1e308, -1e308, 5e-324, NAN, INF])


def sized(rows: int | None, cols: int | None) -> st.SearchStrategy[np.ndarray]:
    """Arrays of any floats; None: a random size (0 to 6)."""
    size = st.integers(0, 6)
    return st.tuples(
        st.just(rows) if rows is not None else size, st.just(cols) if cols is not None else size
    ).flatmap(
        lambda shape: st.lists(
            floats_any, min_size=shape[0] * shape[1], max_size=shape[0] * shape[1]
        ).map(lambda values: np.array(values, dtype=float).reshape(shape))
    )


def vector_of(n: int | None) -> st.SearchStrategy[np.ndarray]:
    return sized(n, 1).map(lambda a: a.reshape(-1))


# (object path, attribute, strategy of values); fixed-size Eigen fields get the right shape,
# dynamic ones any size
CORE_FIELDS: list[tuple[str, str, st.SearchStrategy]] = [
    *[(arm, key, floats_any) for arm in ("plant", "model") for key in ARM_KEYS],
    ("", "disturbance", vector_of(2)),
    ("task", "q0", vector_of(2)),
    ("task", "dq0", vector_of(2)),
    ("task.qd", "kind", st.sampled_from(list(_core.TrajectoryKind.__members__.values()))),
    ("task.qd", "offset", vector_of(2)),
    ("task.qd", "amplitude", sized(2, None)),
    ("task.qd", "frequency", sized(2, None)),
    ("task.qd", "phase", sized(2, None)),
    ("task.qd", "breaks", vector_of(None)),
    ("task.qd", "coefficients", sized(None, 8)),
    ("", "Q", sized(4, 4)),
    ("", "R", sized(2, 2)),
    ("control", "alpha1", sized(2, 2)),
    *[("control.rise", key, floats_any) for key in ("ks", "alpha2", "beta1")],
    *[("critic", key, floats_any) for key in ("eta_c", "nu", "gamma0", "epsilon_T")],
    *[("actor", key, floats_any) for key in ("eta_a1", "eta_a2", "weight_bound", "e2_margin")],
    ("controller", "kind", st.sampled_from(list(_core.ControllerKind.__members__.values()))),
    ("controller", "rise", st.booleans()),
    ("actor", "positive_e2", st.booleans()),
    ("controller", "kp", sized(2, 2)),
    ("controller", "kd", sized(2, 2)),
    ("", "basis", st.sampled_from(list(_core.BasisKind.__members__.values()))),
    ("extrapolation", "points", st.integers(-3, 20) | st.sampled_from([MAX_POINTS + 1, 2**62])),
    ("extrapolation", "box", vector_of(4)),
    ("extrapolation", "mode", st.sampled_from(list(_core.ExtrapolationMode.__members__.values()))),
    ("extrapolation", "seed", st.integers(0, 2**32 - 1)),
    ("", "critic_weights", vector_of(None) | vector_of(8)),
    ("", "actor_weights", vector_of(None) | vector_of(8)),
    ("probe", "amplitude", sized(2, None)),
    ("probe", "until", floats_any),
    ("probe", "ramp", floats_any),
    ("probe", "frequencies", vector_of(None)),
    ("probe", "phases", sized(2, None)),
    ("sim", "T", floats_any),
    ("sim", "dt", floats_any),
    ("sim", "divergence_bound", floats_any),
    ("sim", "record_every", st.integers(-3, 100) | st.sampled_from([2**62, -(2**62)])),
]


def set_core_field(settings: _core.Settings, path: str, key: str, value: Any) -> None:
    """Assigns settings.<path>.<key> = value. pybind11 copies nested structs and Eigen members
    on access, so each level is read, changed and assigned back."""
    if not path:
        setattr(settings, key, value)
        return
    names = path.split(".")
    objects = [settings]
    for name in names:
        objects.append(getattr(objects[-1], name))
    setattr(objects[-1], key, value)
    for parent, name, child in zip(objects[-2::-1], names[::-1], objects[:0:-1], strict=True):
        setattr(parent, name, child)


# the paper's instance on a short horizon, tracking two sinusoids, with local extrapolation
CORE_BASE = adparm.paper_config().updated(
    {
        "sim": {"T": 0.5, "record_every": 7},
        "task": {
            "qd": {
                "kind": "sinusoid",
                "amplitude": [[0.2, 0.1], [0.1, 0.0]],
                "frequency": [[1.0, 3.0], [2.0, 1.0]],
            }
        },
        "extrapolation": {"points": 3, "mode": "local"},
    }
)


# fixed-size Eigen fields given an array of another shape: pybind11 refuses it on assignment
WRONG_SHAPES: list[tuple[str, str, st.SearchStrategy]] = [
    (path, key, sized(None, None).filter(lambda a, shape=shape: a.shape != shape))
    for path, key, shape in [
        ("", "Q", (4, 4)),
        ("", "R", (2, 2)),
        ("control", "alpha1", (2, 2)),
        ("controller", "kp", (2, 2)),
        ("task", "q0", (2, 1)),
        ("extrapolation", "box", (4, 1)),
        ("task.qd", "coefficients", (0, 8)),
    ]
]


@given(
    changes=st.lists(
        st.sampled_from(CORE_FIELDS + WRONG_SHAPES).flatmap(
            lambda field: st.tuples(st.just(field[0]), st.just(field[1]), field[2])
        ),
        min_size=1,
        max_size=4,
    )
)
# found by this test: dt far above T made T / dt underflow to 0 steps, and the run never ended
@example(changes=[("sim", "T", 4.122076585814266e-220), ("sim", "dt", 1e308)])
def test_core_refuses_or_runs_any_settings(changes: list[tuple[str, str, Any]]) -> None:
    settings = core_settings(CORE_BASE)
    for path, key, value in changes:
        try:
            set_core_field(settings, path, key, value)
        except TypeError:  # pybind11: wrong shape for a fixed-size field
            assert (path, key) in {(p, k) for p, k, _ in WRONG_SHAPES}, (path, key)
            event("refused on assignment")
            return
    try:
        run = _core.Simulation(settings)
    except (ValueError, TypeError) as error:
        note(str(error))
        event("refused")
        return
    except MemoryError:  # std::bad_alloc: only for a recording larger than memory
        sim = settings.sim
        assert math.ceil(sim.T / sim.dt) / sim.record_every * 8 > 2**30
        event("MemoryError")
        return
    event("ran")
    run.advance(300)
    assert run.status in ("running", "finished", "diverged")
    assert 0 <= run.step <= min(300, run.steps)
    assert np.all(np.isfinite(run.state))
    recording = run.recording()
    assert recording["t"].size >= (run.status != "diverged")
    for name, value in recording.items():
        assert np.all(np.isfinite(value)), name
