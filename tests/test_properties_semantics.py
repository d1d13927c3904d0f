"""aeroexec's STL engine (aeroexec/properties/: lexer, parser, semantics) against RTAMT's
own offline monitors, the reference for the language and its meaning: the same robustness
at every sample, for every operator and for random formulas written without parentheses
(so the precedence is RTAMT's too). RTAMT is a test dependency only, installed where it
runs (Python < 3.12); the comparisons skip elsewhere. The tests after them need no RTAMT:
Boolean verdicts that agree with the robustness's sign wherever that sign decides, and
an engine that never loads RTAMT."""

from __future__ import annotations

import contextlib
import io
import random
import subprocess
import sys

import numpy as np
import pytest

from aeroexec.errors import Mark
from aeroexec.properties import semantics
from aeroexec.properties.formula import compile_formula
from aeroexec.properties.signals import is_known_signal

FORMULAS = [
    "always(altitude <= 1.2)",
    "eventually(speed > 0.5)",
    "historically(battery >= 0.3)",
    "once(altitude == 0.5)",
    "G(altitude < 0.9) or F(speed >= 0.9)",
    "H(battery > 0.1) and O(altitude <= 0.2)",
    "always((altitude > 0.5) implies eventually[0:1.5](speed < 0.3))",
    "always[0.2:1](altitude !== 0.4) or eventually[0.3:0.7](battery > 0.6)",
    "historically[0:0.8](speed <= 0.7) and once[0.1:0.5](battery > 0.2)",
    "always[200ms:1s](altitude < 0.8) or eventually[0, 500 ms](speed > 0.6)",
    "(altitude > 0.3) until (speed > 0.8)",
    "(altitude > 0.3) since (speed > 0.8)",
    "(altitude > 0.2) until[0.1:0.6] (speed > 0.8)",
    "(altitude > 0.2) until[0:0.5] (speed > 0.8)",
    "(altitude > 0.2) since[0:0.5] (speed > 0.8)",
    "(altitude > 0.2) since[0.3:1.2] (speed > 0.8)",
    "(altitude > 0.2) U[0.2:0.4] (speed > 0.8) or (battery < 0.5) S (speed > 0.5)",
    "(altitude > 0.2) unless[0.1:0.5] (speed > 0.8)",
    "(altitude > 0.2) W[0:0.3] (speed > 0.8)",
    "eventually[0 us:300000 us](speed > 0.9) or once[0 ns:200000000 ns](battery > 0.7)",
    "not(altitude >= 0.5) iff (speed < 0.5)",
    "(altitude >= 0.5) xor (speed < 0.5)",
    "!(altitude > 0.5) | (speed < 0.3) & (battery > 0.4) -> (altitude < 0.7) <-> (speed > 0.1)",
    "rise(altitude >= 0.5) or fall(speed >= 0.5)",
    "prev(altitude >= 0.5) and next(speed >= 0.5)",
    "Y(altitude >= 0.5) and X(speed >= 0.5)",
    "always(abs(altitude - speed) + sqrt(battery) * 2 - exp(speed) / 3 <= 1.5)",
    "always(pow(altitude, 2) + pow(speed, 0.5) <= 1.1)",
    "altitude - speed + battery >= -0.5",
    "altitude / 2 * 3 + battery < speed * 3 / 2 - altitude - battery",
    "always(altitude <= 1_0 / 10) /* a comment */ and eventually(speed > .5e0) // to the end",
    "not altitude > 0.5 and speed > 0.5 until[0:0.3] battery > 0.5 or altitude < 0.2",
]
LENGTH = 300


def columns(seed: int) -> dict[str, np.ndarray]:
    rng = np.random.default_rng(seed)
    # Quantized values make equal samples (the boundaries of == and !==) common.
    return {name: np.round(rng.random(LENGTH), 1) for name in ("altitude", "speed", "battery")}


def rtamt_series(text: str, data: dict[str, np.ndarray]) -> np.ndarray:
    """RTAMT's own offline robustness of `text` on `data`, sampled every 0.1 s (an
    RTAMTException where RTAMT's parser refuses the text)."""
    rtamt = pytest.importorskip(
        "rtamt",
        reason="RTAMT, the reference, is not installed (the test extra has it on Python < 3.12)",
    )
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


def ours(text: str, data: dict[str, np.ndarray]) -> np.ndarray:
    formula = compile_formula(text, Mark("t.yaml"), is_known_signal)
    return formula.robustness(data, LENGTH)


@pytest.mark.parametrize("text", FORMULAS)
@pytest.mark.parametrize("seed", [1, 2, 3])
def test_robustness_is_rtamts_at_every_sample(text: str, seed: int) -> None:
    data = columns(seed)
    expected = rtamt_series(text, data)
    np.testing.assert_allclose(ours(text, data), expected, rtol=1e-12, atol=1e-12)


# -- random formulas, written with as few parentheses as the text allows --------------------------
SIGNALS = ("altitude", "speed", "battery")


def arithmetic(rng: random.Random, depth: int) -> str:
    roll = rng.random()
    if depth <= 0 or roll < 0.35:
        return rng.choice([*SIGNALS, "0.5", "2", "1.5", "-0.3"])
    if roll < 0.45:
        return f"abs({arithmetic(rng, depth - 1)})"
    op = rng.choice(["+", "-", "*", "/"])
    # Divisors built from these operands are never 0 on the signals below (all >= 0.1).
    right = rng.choice([*SIGNALS, "2", "0.5"]) if op == "/" else arithmetic(rng, depth - 1)
    return f"{arithmetic(rng, depth - 1)} {op} {right}"


def window(rng: random.Random) -> str:
    begin = rng.randint(0, 4)
    return f"[{begin / 10:g}:{(begin + rng.randint(0, 6)) / 10:g}]"


def boolean(rng: random.Random, depth: int) -> str:
    roll = rng.random()
    if depth <= 0 or roll < 0.2:
        op = rng.choice(["<", "<=", ">", ">=", "==", "!=="])
        return f"{arithmetic(rng, 1)} {op} {arithmetic(rng, 1)}"
    if roll < 0.45:
        op = rng.choice(["not", "always", "eventually", "historically", "once", "prev", "next"])
        bounds = window(rng) if op not in ("not", "prev", "next") and rng.random() < 0.6 else ""
        inner = boolean(rng, depth - 1)
        # A prefix operator takes the operand up to its comparisons: parenthesize at will.
        return f"{op}{bounds}({inner})" if rng.random() < 0.5 else f"{op}{bounds} {inner}"
    if roll < 0.5:
        return f"{rng.choice(['rise', 'fall'])}({boolean(rng, depth - 1)})"
    op = rng.choice(["and", "or", "implies", "iff", "xor", "until", "since", "unless"])
    bounds = window(rng) if op in ("until", "since", "unless") and rng.random() < 0.6 else ""
    if op == "unless" and not bounds:
        bounds = window(rng)  # RTAMT's unless without bounds fails in RTAMT itself
    left, right = boolean(rng, depth - 1), boolean(rng, depth - 1)
    if rng.random() < 0.3:
        left = f"({left})"
    return f"{left} {op}{bounds} {right}"


@pytest.mark.parametrize("seed", range(100))
def test_random_formulas_parse_and_evaluate_as_in_rtamt(seed: int) -> None:
    rng = random.Random(seed)
    data = {name: values + 0.1 for name, values in columns(seed).items()}
    for _ in range(50):
        text = boolean(rng, 3)
        try:
            expected = rtamt_series(text, data)
            break
        except Exception as exc:  # RTAMT's parser reports some ambiguities as errors
            assert "full context" in str(exc), text
    else:
        pytest.fail("RTAMT refused 50 formulas in a row")
    np.testing.assert_allclose(ours(text, data), expected, rtol=1e-9, atol=1e-12, err_msg=text)


# -- Boolean verdicts -----------------------------------------------------------------------------
#: The robustness of iff and xor (-|l - r|, |l - r|) does not follow the truth of its
#: operands (both true by different margins: negative), so its sign decides nothing.
SOUND = [f for f in FORMULAS if not any(w in f for w in ("iff", "xor", "<->"))]


@pytest.mark.parametrize("text", SOUND)
def test_boolean_verdicts_agree_with_every_deciding_robustness(text: str) -> None:
    data = columns(7)
    formula = compile_formula(text, Mark("t.yaml"), is_known_signal)
    robust = formula.robustness(data, LENGTH)
    verdict = formula.verdicts(data, LENGTH)
    assert set(np.unique(verdict)) <= {-np.inf, -1.0, 1.0, np.inf}
    deciding = (robust != 0) & ~np.isnan(robust)
    assert deciding.any()
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
        assert np.array_equal(formula.verdicts(data, LENGTH) > 0, truth), text


def test_timed_until_looks_exactly_its_window_ahead() -> None:
    # p holds from 0 to 4, q only at 6: q is 6 ticks ahead of sample 0 and p must hold on
    # every sample before it (samples 0-5); p fails at 5, so only windows reaching 6 from
    # a start of 5 or later... none: sample 5 has p false. From 6 itself q holds at d=0.
    p = np.array([1.0] * 5 + [0.0] * 5)
    q = np.array([0.0] * 6 + [1.0] + [0.0] * 3)
    data = {"altitude": p, "speed": q}
    formula = compile_formula(
        "(altitude >= 1) until[0:0.6] (speed >= 1)", Mark("t.yaml"), is_known_signal
    )
    assert (formula.verdicts(data, 10) > 0).tolist() == [False] * 6 + [True] + [False] * 3
    p[5] = 1.0  # now p holds on 0-5: q at 6 is reached from 0 (d = 6) but not with [0:0.5]
    assert (formula.verdicts(data, 10) > 0).tolist() == [True] * 7 + [False] * 3
    short = compile_formula(
        "(altitude >= 1) until[0:0.5] (speed >= 1)", Mark("t.yaml"), is_known_signal
    )
    assert (short.verdicts(data, 10) > 0).tolist() == [False] + [True] * 6 + [False] * 3
    assert semantics.series(short.tree, data, 10).shape == (10,)


@pytest.mark.parametrize(
    ("text", "same_as"),
    [
        # Where RTAMT's parser crashed, the text means what it says.
        (
            "(altitude > 0.3) unless (speed > 0.6)",
            "always(altitude > 0.3) or (altitude > 0.3) until (speed > 0.6)",
        ),
        ("always[0 s:1](speed < 0.9)", "always[0:1](speed < 0.9)"),
        # Short forms, symbols, units and separators are the words they stand for.
        (
            "G[100ms:500ms](altitude > 0.2) -> F(speed > 0.5)",
            "always[0.1:0.5](altitude > 0.2) implies eventually(speed > 0.5)",
        ),
        (
            "!(altitude > 0.5) & (speed < 0.5) | (battery > 0.5)",
            "not(altitude > 0.5) and (speed < 0.5) or (battery > 0.5)",
        ),
        ("altitude - speed + battery > 0", "altitude - (speed + battery) > 0"),  # RTAMT's levels
    ],
)
def test_texts_that_mean_the_same(text: str, same_as: str) -> None:
    data = columns(11)
    np.testing.assert_array_equal(ours(text, data), ours(same_as, data))
    assert (
        ours("altitude - speed + battery > 0", data).tolist()
        != ours("(altitude - speed) + battery > 0", data).tolist()
    )


def test_the_engine_never_loads_rtamt_or_antlr() -> None:
    code = (
        "import sys\n"
        "from aeroexec.properties.spec import load_properties\n"
        "from aeroexec.properties.check import evaluate\n"
        "from aeroexec.properties.signals import SignalBuilder\n"
        "b = SignalBuilder(None)\n"
        "b.topic('vehicle/state', 0, {'flying': False, 'armed': False})\n"
        "evaluate(load_properties(['aeroexec:safety']), b.finish())\n"
        "print(sorted(m for m in sys.modules if m.split('.')[0] in ('rtamt', 'antlr4')))\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"


# -- long windows and one sample at a time (what the online monitor uses) --------------------------
@pytest.mark.parametrize("op", ["always", "eventually", "historically", "once"])
def test_long_windows_reduce_exactly_the_samples_they_cover(op: str) -> None:
    # Windows longer than a few samples are reduced block-wise (van Herk/Gil-Werman): the
    # same values as the definition, NaN and infinities included, at both ends.
    rng = np.random.default_rng(5)
    x = np.round(rng.random(400), 2)
    x[rng.random(400) < 0.03] = np.nan
    x[rng.random(400) < 0.03] = np.inf
    x[rng.random(400) < 0.03] = -np.inf
    ahead = op in ("always", "eventually")
    low = op in ("always", "historically")
    for begin, end in ((0, 9), (3, 40), (0, 300), (17, 450)):
        formula = compile_formula(
            f"{op}[{begin / 10:g}:{end / 10:g}](altitude)", Mark("t.yaml"), is_known_signal
        )
        got = formula.robustness({"altitude": x}, len(x))
        expected = []
        for i in range(len(x)):
            span = range(i + begin, i + end + 1) if ahead else range(i - end, i - begin + 1)
            pad = np.inf if low else -np.inf
            inside = [x[j] if 0 <= j < len(x) else pad for j in span]
            expected.append(np.min(inside) if low else np.max(inside))
        np.testing.assert_array_equal(got, expected, err_msg=f"{op}[{begin}:{end}]")


def instant_boolean(rng: random.Random, depth: int) -> str:
    roll = rng.random()
    if depth <= 0 or roll < 0.3:
        op = rng.choice(["<", "<=", ">", ">=", "==", "!=="])
        left = arithmetic(rng, 1) if rng.random() < 0.8 else f"sqrt({arithmetic(rng, 1)})"
        return f"{left} {op} {arithmetic(rng, 1)}"
    if roll < 0.4:
        return f"not({instant_boolean(rng, depth - 1)})"
    if roll < 0.45:
        return rng.choice(SIGNALS)  # a signal as a formula: its value is the verdict
    op = rng.choice(["and", "or", "implies", "iff", "xor", "->", "&", "|"])
    return f"({instant_boolean(rng, depth - 1)}) {op} ({instant_boolean(rng, depth - 1)})"


@pytest.mark.parametrize("seed", range(40))
def test_one_sample_at_a_time_gives_the_arrays_verdict(seed: int) -> None:
    # The monitor judges bodies without temporal operators tick by tick on Python floats
    # (semantics.instant): at every sample the same verdict as the arrays, and the same
    # value but for a zero's sign, or an error where numpy makes an inf or a nan of one.
    rng = random.Random(seed)
    values = [0.0, -0.0, 0.5, -0.5, 1.0, 2.0, -3.0, np.inf, -np.inf, np.nan, 1e308, 0.1]
    data = {name: np.array([rng.choice(values) for _ in range(60)]) for name in SIGNALS}
    judged = 0
    for _ in range(10):
        text = instant_boolean(rng, 3)
        tree = compile_formula(text, Mark("t.yaml"), is_known_signal).tree
        at = semantics.instant(tree)
        assert at is not None, text
        arrays = semantics.series(tree, data, 60, boolean=True)
        for i in range(60):
            sample = {name: float(column[i]) for name, column in data.items()}
            try:
                value = at(sample)
            except (ArithmeticError, ValueError):
                continue
            judged += 1
            assert (value < 0) == (arrays[i] < 0), (text, i)
            assert value == arrays[i] or (np.isnan(value) and np.isnan(arrays[i])), (text, i)
    assert judged > 300  # most samples are judged this way


def test_only_bodies_of_the_present_sample_are_judged_one_sample_at_a_time() -> None:
    for text in (
        "eventually[0:1](altitude > 1)",
        "prev(altitude > 1)",
        "rise(altitude > 1)",
        "(altitude > 1) until (speed > 1)",
        "exp(altitude) > 1",  # Python's math and numpy may round exp and pow apart
        "pow(altitude, 2) > 1",
    ):
        tree = compile_formula(text, Mark("t.yaml"), is_known_signal).tree
        assert semantics.instant(tree) is None, text
    at = semantics.instant(compile_formula("altitude / speed > 1", Mark("t"), is_known_signal).tree)
    assert at is not None
    with pytest.raises(ZeroDivisionError):  # numpy: inf; the monitor judges it on arrays
        at({"altitude": 1.0, "speed": 0.0})


@pytest.mark.parametrize("seed", range(30))
def test_a_propertys_robustness_is_its_series_at_the_start(seed: int) -> None:
    # `evaluate` reads a property's robustness with `at_start`, which reduces the
    # operand of a whole-trace operator at the top instead of building its series: the
    # same float, NaN (a signal that is no number) included.
    rng = random.Random(seed)
    data = {name: values + 0.1 for name, values in columns(seed).items()}
    if seed % 3 == 0:
        data["speed"][rng.randrange(LENGTH)] = np.nan
    for top in ("always", "eventually", "historically", "once", "always[0:0.5]", ""):
        text = f"{top}({boolean(rng, 2)})" if top else boolean(rng, 2)
        node = compile_formula(text, Mark("t.yaml"), is_known_signal).tree
        whole = semantics.series(node, data, LENGTH)[0]
        start = semantics.at_start(node, data, LENGTH)
        assert start == whole or (np.isnan(start) and np.isnan(whole)), text
