"""Symbolic kinematics (sympy) against the numeric chains, each other, and the reports' closed forms."""

import math
import subprocess
import sys
from typing import Any

import numpy as np
import pytest

sp = pytest.importorskip("sympy")
symbolic = pytest.importorskip("hexabot_sim.kinematics.symbolic")

from hexabot_sim.errors import HexabotError, UsageError  # noqa: E402
from hexabot_sim.kinematics import robots  # noqa: E402
from hexabot_sim.kinematics.chain import Joint, SerialChain  # noqa: E402

ROBOTS = ("rrp", "elbow", "scara", "leg", "stanford")  # all of robots.ROBOTS; the Stanford arm takes ~1 s
THREE_DOF = ("rrp", "elbow", "leg")
N = 50  # random configurations per robot
TOL = 1e-12


@pytest.fixture(scope="module")
def chains() -> dict:
    """Each robot's symbolic chain, built once (its transforms and Jacobians are cached on it)."""
    return {name: symbolic.symbolic_chain(name) for name in ROBOTS}


def test_robot_list_is_complete() -> None:
    assert set(ROBOTS) == set(robots.ROBOTS)


@pytest.mark.slow
@pytest.mark.parametrize("name", ROBOTS)
def test_lambdified_matches_numeric_chain(chains: dict, name: str) -> None:
    """T01..T0tool, J (direct) and J (differentiation), evaluated, equal the numeric chain's frames and Jacobian.

    Half the points use the default lengths, half random ones, so a swapped pair of equal defaults (the RRP's
    d1 = a2 = 1 m) cannot hide.
    """
    sc = chains[name]
    spec = robots.get(name)
    frames = symbolic.transforms(sc)
    evaluate = sp.lambdify(
        sc.symbols, [*frames, symbolic.jacobian(sc), symbolic.jacobian_by_differentiation(sc)], "numpy"
    )
    rng = np.random.default_rng(7)
    for k in range(N):
        q = np.where(sc.prismatic, rng.uniform(-0.5, 1.5, sc.n), rng.uniform(-math.pi, math.pi, sc.n))  # (n,)
        lengths = sc.defaults if k % 2 == 0 else {key: rng.uniform(0.05, 1.0) for key in sc.lengths}
        chain = spec.chain(lengths)
        *poses, jac, jac_diff = (np.asarray(m, dtype=float) for m in evaluate(*q, *(lengths[n] for n in sc.lengths)))
        np.testing.assert_allclose(poses, chain.frames(q)[1:], rtol=0, atol=TOL)
        np.testing.assert_allclose(jac, chain.jacobian(q), rtol=0, atol=TOL)
        np.testing.assert_allclose(jac_diff, chain.jacobian(q), rtol=0, atol=TOL)


def test_symbols_are_named_like_the_reports(chains: dict) -> None:
    assert [str(s) for s in chains["rrp"].q] == ["q1", "q2", "d3"]
    assert [str(s) for s in chains["stanford"].q] == ["q1", "q2", "d3", "q4", "q5", "q6"]
    assert [str(s) for s in chains["scara"].q] == ["q1", "q2", "d3", "q4"]
    for name in ROBOTS:
        assert list(chains[name].lengths) == list(robots.get(name).lengths)
        assert dict(chains[name].defaults) == {k: v.default for k, v in robots.get(name).lengths.items()}
    # Twists stay exact: the leg's A2 has cos(-π/2) = 0 exactly, no 6e-17.
    assert chains["leg"].links[1][1, 1] == 0
    assert chains["leg"].links[1][1, 2] == 1


@pytest.mark.parametrize("name", ROBOTS)
def test_direct_and_differentiation_jacobians_are_identical(chains: dict, name: str) -> None:
    sc = chains[name]
    assert sp.simplify(symbolic.jacobian(sc) - symbolic.jacobian_by_differentiation(sc)) == sp.zeros(6, sc.n)


@pytest.mark.slow
@pytest.mark.parametrize("name", THREE_DOF)
def test_unsimplified_jacobians_are_equal_by_sympy_simplify(name: str) -> None:
    """Without the module's own simplifier: sympy.simplify proves the raw direct and differentiated J equal."""
    sc = symbolic.symbolic_chain(name)
    difference = symbolic.jacobian(sc, simplify=False) - symbolic.jacobian_by_differentiation(sc, simplify=False)
    assert sp.simplify(difference) == sp.zeros(6, sc.n)


@pytest.mark.slow
def test_leg_matches_report_000(chains: dict) -> None:
    """Report 000: T04 (eq. 8), the Jacobian (eq. 15) and det Jv = l2 l3 sin q3 (l1 + l2 c2 + l3 c23), same sign."""
    sc = chains["leg"]
    q1, q2, q3 = sc.q
    l1, l2, l3 = (sc.lengths[k] for k in ("l1", "l2", "l3"))
    c1, s1, c2, s2 = sp.cos(q1), sp.sin(q1), sp.cos(q2), sp.sin(q2)
    c23, s23 = sp.cos(q2 + q3), sp.sin(q2 + q3)
    rho = l1 + l2 * c2 + l3 * c23
    report_t04 = sp.Matrix(
        [
            [c1 * c23, -c1 * s23, -s1, c1 * rho],
            [s1 * c23, -s1 * s23, c1, s1 * rho],
            [-s23, -c23, 0, -l2 * s2 - l3 * s23],
            [0, 0, 0, 1],
        ]
    )
    report_jv = sp.Matrix(
        [
            [-s1 * rho, -c1 * (s2 * l2 + s23 * l3), -c1 * s23 * l3],
            [c1 * rho, -s1 * (s2 * l2 + s23 * l3), -s1 * s23 * l3],
            [0, -c2 * l2 - c23 * l3, -c23 * l3],
        ]
    )
    t04 = symbolic.transforms(sc)[-1]
    jv = symbolic.jacobian(sc)[:3, :]
    assert sp.simplify(t04[:3, 3] - sp.Matrix([c1 * rho, s1 * rho, -l2 * s2 - l3 * s23])) == sp.zeros(3, 1)
    assert sp.simplify(t04 - report_t04) == sp.zeros(4, 4)
    assert sp.simplify(jv - report_jv) == sp.zeros(3, 3)
    # The simplified forms are the report's term for term, not merely equal to them.
    assert t04 == report_t04
    assert jv == report_jv
    det = sp.simplify(jv.det())
    assert sp.simplify(det - l2 * l3 * sp.sin(q3) * rho) == 0  # same sign as the report and leg.det_jacobian


def test_rrp_matches_report_001(chains: dict) -> None:
    """Report 001: H = Rz(q1) Tz(d1) Ry(-q2) Tx(a2) Tx(d3) is the tool pose; Jv = dp/dq of its position."""
    sc = chains["rrp"]
    q1, q2, d3 = sc.q
    d1, a2 = sc.lengths["d1"], sc.lengths["a2"]

    def rz(t: Any) -> Any:
        return sp.Matrix([[sp.cos(t), -sp.sin(t), 0, 0], [sp.sin(t), sp.cos(t), 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])

    def ry(t: Any) -> Any:
        return sp.Matrix([[sp.cos(t), 0, sp.sin(t), 0], [0, 1, 0, 0], [-sp.sin(t), 0, sp.cos(t), 0], [0, 0, 0, 1]])

    def tx(x: Any) -> Any:
        return sp.Matrix([[1, 0, 0, x], [0, 1, 0, 0], [0, 0, 1, 0], [0, 0, 0, 1]])

    def tz(z: Any) -> Any:
        return sp.Matrix([[1, 0, 0, 0], [0, 1, 0, 0], [0, 0, 1, z], [0, 0, 0, 1]])

    h = rz(q1) * tz(d1) * ry(-q2) * tx(a2) * tx(d3)
    jv = h[:3, 3].jacobian(sp.Matrix(sc.q))
    assert sp.simplify(symbolic.jacobian(sc)[:3, :] - jv) == sp.zeros(3, 3)
    assert sp.simplify(symbolic.transforms(sc)[-1] - h) == sp.zeros(4, 4)
    # The report's printed position: (c1 c2 (a2 + d3), c2 s1 (a2 + d3), d1 + a2 s2 + d3 s2).
    c1, s1, c2, s2 = sp.cos(q1), sp.sin(q1), sp.cos(q2), sp.sin(q2)
    report_p = sp.Matrix([c1 * c2 * (a2 + d3), c2 * s1 * (a2 + d3), d1 + a2 * s2 + d3 * s2])
    assert sp.simplify(h[:3, 3] - report_p) == sp.zeros(3, 1)


def test_stanford_position_matches_report_003(chains: dict) -> None:
    """Report 003 problem 2: dx, dy, dz of T06."""
    sc = chains["stanford"]
    q1, q2, d3, q4, q5, _ = sc.q
    d2, d6 = sc.lengths["d2"], sc.lengths["d6"]
    c1, s1, c2, s2, c4, s4, c5, s5 = (f(q) for q in (q1, q2, q4, q5) for f in (sp.cos, sp.sin))
    report = sp.Matrix(
        [
            c1 * d3 * s2 - d6 * (s5 * (s1 * s4 - c1 * c2 * c4) - c1 * c5 * s2) - d2 * s1,
            c1 * d2 + d6 * (s5 * (c1 * s4 + c2 * c4 * s1) + c5 * s1 * s2) + d3 * s1 * s2,
            c2 * d3 + d6 * (c2 * c5 - c4 * s2 * s5),
        ]
    )
    assert sp.expand(symbolic.transforms(sc)[-1][:3, 3] - report) == sp.zeros(3, 1)


def test_pretty_and_latex_abbreviate_like_the_reports(chains: dict) -> None:
    t04 = symbolic.transforms(chains["leg"])[-1]
    text = symbolic.pretty(t04)
    for short in ("c1", "s1", "c2", "s2", "c23", "s23"):
        assert short in text
    assert "cos" not in text and "sin" not in text
    assert "cos(q2 + q3)" in symbolic.pretty(t04, abbreviate=False)
    tex = symbolic.latex(t04)
    assert "c_{23}" in tex and "s_{1}" in tex and r"\cos" not in tex
    assert r"\cos" in symbolic.latex(t04, abbreviate=False)
    listing = symbolic.listing(t04, "T04").splitlines()
    assert len(listing) == 16 and listing[0] == "T0411 = c1*c23"


def test_abbreviation_rules() -> None:
    q1, q2, q3, x = sp.symbols("q1 q2 q3 x", real=True)
    out = symbolic.abbreviated(sp.cos(q3 + q2) + sp.sin(q1) + sp.cos(q2 - q3) + sp.sin(x) + sp.cos(2 * q1))
    names = {str(s) for s in out.free_symbols}
    assert {"c23", "s1"} <= names
    assert sp.cos(q2 - q3) in out.atoms(sp.cos)  # a difference is not a report abbreviation
    assert sp.sin(x) in out.atoms(sp.sin) and sp.cos(2 * q1) in out.atoms(sp.cos)


def test_from_chain_names_the_given_lengths(chains: dict) -> None:
    spec = robots.get("leg")
    lengths = {"l1": 0.05, "l2": 0.1, "l3": 0.12}
    sc = symbolic.from_chain(spec.chain(lengths), lengths)
    assert sp.simplify(symbolic.transforms(sc)[-1] - symbolic.transforms(chains["leg"])[-1]) == sp.zeros(4, 4)
    with pytest.raises(UsageError, match="'l2' and 'l3' have the same value"):
        symbolic.from_chain(spec.chain(), {"l1": 0.05, "l2": 0.1, "l3": 0.1})
    with pytest.raises(UsageError, match="non-zero"):
        symbolic.from_chain(spec.chain(), {"l1": 0.0})


def test_from_chain_keeps_unnamed_numbers_and_odd_angles() -> None:
    chain = SerialChain("two", (Joint("a", a=0.3, alpha=math.pi / 3), Joint("b", a=0.25, theta=0.1)))
    sc = symbolic.from_chain(chain, {"a1": 0.3})
    assert sc.links[0][2, 1] == sp.sin(sp.pi / 3)  # exact twist
    assert sc.links[1][0, 3].atoms(sp.Float) == {sp.Float(0.25), sp.Float(0.1)}  # a = 0.25 was not named
    evaluate = sp.lambdify(sc.symbols, symbolic.transforms(sc)[-1], "numpy")
    q = np.array([0.4, -1.1])
    np.testing.assert_allclose(evaluate(*q, 0.3), chain.fk(q), rtol=0, atol=TOL)


def test_unrecognised_use_of_a_length_raises(monkeypatch: pytest.MonkeyPatch) -> None:
    """A length entering the table through a formula (here 2·l) must not freeze the marker value into T."""
    spec = robots.RobotSpec(
        "double",
        "test robot",
        {"l": robots.Length(0.1, "link")},
        lambda p: SerialChain("double", (Joint("j", a=2 * p["l"]),)),
        ("rad",),
    )
    monkeypatch.setitem(robots.ROBOTS, "double", spec)
    with pytest.raises(HexabotError, match="not ± one of the lengths l"):
        symbolic.symbolic_chain("double")
    with pytest.raises(UsageError, match="unknown robot"):
        symbolic.symbolic_chain("nope")


def test_package_imports_without_sympy() -> None:
    """hexabot_sim, its kinematics and its CLI import with sympy unavailable; this module says what to install."""
    code = (
        "import sys\n"
        "sys.modules['sympy'] = None\n"
        "import hexabot_sim, hexabot_sim.kinematics.robots, hexabot_sim.kinematics.chain, hexabot_sim.__main__\n"
        "try:\n"
        "    import hexabot_sim.kinematics.symbolic\n"
        "except ImportError as exc:\n"
        "    print(exc)\n"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, timeout=60, check=False)
    assert done.returncode == 0, done.stderr
    assert "hexabot-sim[symbolic]" in done.stdout
