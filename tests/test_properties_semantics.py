"""aeroexec's array semantics (aeroexec/properties/semantics.py) against RTAMT's own
offline monitors: the same robustness at every sample, for every operator; and Boolean
verdicts that agree with the robustness's sign wherever that sign decides."""

from __future__ import annotations

import contextlib
import io

import numpy as np
import pytest
import rtamt

from aeroexec.errors import Mark
from aeroexec.properties import semantics
from aeroexec.properties.formula import compile_formula
from aeroexec.properties.signals import is_known_signal

FORMULAS = [
    "always(altitude <= 1.2)",
    "eventually(speed > 0.5)",
    "historically(battery >= 0.3)",
    "once(altitude == 0.5)",
    "always((altitude > 0.5) implies eventually[0:1.5](speed < 0.3))",
    "always[0.2:1](altitude !== 0.4) or eventually[0.3:0.7](battery > 0.6)",
    "historically[0:0.8](speed <= 0.7) and once[0.1:0.5](battery > 0.2)",
    "(altitude > 0.3) until (speed > 0.8)",
    "(altitude > 0.3) since (speed > 0.8)",
    "(altitude > 0.2) until[0.1:0.6] (speed > 0.8)",
    "(altitude > 0.2) since[0:0.5] (speed > 0.8)",
    "not(altitude >= 0.5) iff (speed < 0.5)",
    "(altitude >= 0.5) xor (speed < 0.5)",
    "rise(altitude >= 0.5) or fall(speed >= 0.5)",
    "prev(altitude >= 0.5) and next(speed >= 0.5)",
    "always(abs(altitude - speed) + sqrt(battery) * 2 - exp(speed) / 3 <= 1.5)",
]
LENGTH = 300


def columns(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    # Quantized values make equal samples (the boundaries of == and !=) common.
    return {name: np.round(rng.random(LENGTH), 1) for name in ("altitude", "speed", "battery")}


def rtamt_series(text: str, data: dict[str, np.ndarray]) -> np.ndarray:
    spec = rtamt.StlDiscreteTimeOfflineSpecification()
    names = [n for n in data if n in text]
    for name in names:
        spec.declare_var(name, "float")
    spec.spec = text
    spec.set_sampling_period(100, "ms", 0.1)
    with contextlib.redirect_stdout(io.StringIO()):
        spec.parse()
        dataset = {"time": [k * 0.1 for k in range(LENGTH)]}
        dataset |= {n: data[n].tolist() for n in names}
        return np.array([v for _, v in spec.evaluate(dataset)])


@pytest.mark.parametrize("text", FORMULAS)
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_robustness_is_rtamts_at_every_sample(text: str, seed: int) -> None:
    data = columns(seed)
    formula = compile_formula(text, Mark("t.yaml"), is_known_signal)
    ours = semantics.run(formula._spec, formula.top, dict(data), LENGTH)
    expected = rtamt_series(text, data)
    np.testing.assert_allclose(ours, expected, rtol=1e-12, atol=1e-12)


#: RTAMT's robustness of iff and xor (-|l - r|, |l - r|) does not follow the truth of
#: its operands (both true by different margins: negative), so its sign decides nothing.
SOUND = [f for f in FORMULAS if "iff" not in f and "xor" not in f]


@pytest.mark.parametrize("text", SOUND)
def test_boolean_verdicts_agree_with_every_deciding_robustness(text: str) -> None:
    data = columns(7)
    formula = compile_formula(text, Mark("t.yaml"), is_known_signal)
    robust = semantics.run(formula._spec, formula.top, dict(data), LENGTH)
    verdict = semantics.run(formula._boolean, formula.top, dict(data), LENGTH)
    assert set(np.unique(verdict)) <= {-np.inf, -1.0, 1.0, np.inf}
    deciding = robust != 0
    assert np.array_equal(verdict[deciding] > 0, robust[deciding] > 0)


def test_iff_and_xor_verdicts_follow_their_truth_tables() -> None:
    data = columns(9)
    a = data["altitude"] >= 0.5
    b = data["speed"] < 0.5
    for text, truth in (
        ("(altitude >= 0.5) iff (speed < 0.5)", a == b),
        ("(altitude >= 0.5) xor (speed < 0.5)", a != b),
    ):
        formula = compile_formula(text, Mark("t.yaml"), is_known_signal)
        verdict = semantics.run(formula._boolean, formula.top, dict(data), LENGTH)
        assert np.array_equal(verdict > 0, truth), text
