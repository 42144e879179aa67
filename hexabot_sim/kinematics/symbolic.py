"""Symbolic DH kinematics with sympy (the optional `symbolic` extra): T0i, Jacobians, c1/s23-style printing."""

from __future__ import annotations

import dataclasses
import functools
import math
import re
from collections.abc import Mapping, Sequence
from fractions import Fraction
from typing import Any

import numpy as np

from hexabot_sim.errors import HexabotError, UsageError
from hexabot_sim.kinematics import robots
from hexabot_sim.kinematics.chain import Joint, SerialChain
from hexabot_sim.kinematics.robot_file import MISREAD_SYMBOL

try:
    import sympy as sp  # type: ignore[import-untyped]
    from sympy.simplify.fu import TR10i  # type: ignore[import-untyped]
except ImportError as exc:  # pragma: no cover - exercised only without the extra
    raise ImportError(
        "hexabot_sim.kinematics.symbolic needs sympy; install the extra: pip install 'hexabot-sim[symbolic]'"
    ) from exc

# A DH or tool entry within this of a named length (relative), of 0, or of an exact constant is taken as it.
MATCH_TOL: float = 1e-12
# Twists and angle offsets are written k·π/m for denominators m up to this; other angles stay floats.
MAX_PI_DENOMINATOR: int = 12
# Exact values recognised in the rotation part of base and tool transforms.
_UNIT_CONSTANTS = (sp.Integer(0), sp.Integer(1), sp.Rational(1, 2), sp.sqrt(2) / 2, sp.sqrt(3) / 2)
# `kin --symbolic` stops when a simplified T0i has more operations than this (sympy.count_ops): measured here, a
# 7-joint arm with 90 deg twists reaches 1904 and takes 42 s in all; five joints with 37 deg twists reach 3424 and
# take 78 s, six of them minutes (the package's robots: at most 315, the Stanford arm).
MAX_OPS: int = 2000
# Revolute joint symbols are q1..qn; cos/sin of a sum of them abbreviate to c1, s23, ...
_JOINT_SYMBOL = re.compile(r"q(\d+)")


@dataclasses.dataclass(frozen=True, eq=False)
class SymbolicChain:
    """A serial chain with symbolic joint variables and link lengths; build it with `symbolic_chain` or `from_chain`.

    Attributes:
        name: Robot name.
        convention: "standard" (joint about z_{i-1}) or "modified" (joint about z_i) DH.
        q: Joint symbols, base to tip: q<i> for revolute joints, the joint's name (e.g. d3) for prismatic ones.
        prismatic: For each joint, True if prismatic.
        lengths: Link-length symbols by name (d1, a2, l1, ...), as in `robots.get(name).lengths`.
        defaults: The robot's numeric value of each length in [m] (substitute them to compare with `chain()`).
        links: Link transforms A_1..A_n (frame i-1 to frame i), each a 4x4 `sympy.ImmutableMatrix`.
        base: World to frame 0, 4x4.
        tool: Frame n to the tool frame, 4x4.
    """

    name: str
    convention: str
    q: tuple[sp.Symbol, ...]
    prismatic: tuple[bool, ...]
    lengths: Mapping[str, sp.Symbol]
    defaults: Mapping[str, float]
    links: tuple[sp.ImmutableMatrix, ...]
    base: sp.ImmutableMatrix
    tool: sp.ImmutableMatrix
    # Results of transforms/jacobian by (function, simplify); not an init field, so `replace` starts afresh.
    _cache: dict[tuple[str, bool], Any] = dataclasses.field(default_factory=dict, init=False, repr=False)

    @property
    def n(self) -> int:
        """Number of joints."""
        return len(self.q)

    @property
    def symbols(self) -> tuple[sp.Symbol, ...]:
        """All free symbols in argument order for `sympy.lambdify`: joints, then lengths."""
        return (*self.q, *self.lengths.values())

    def default_values(self) -> tuple[float, ...]:
        """The default lengths in [m], in the order of `lengths` (to follow q in a lambdified call)."""
        return tuple(self.defaults[name] for name in self.lengths)


def symbolic_chain(robot: str | robots.RobotSpec) -> SymbolicChain:
    """The symbolic chain of a robot (a name in `robots.ROBOTS`, or any RobotSpec, e.g. a robot file's), with its
    named link lengths as symbols.

    The robot's own `build` makes the numeric chain with a distinct marker value for each length; every DH
    entry, base and tool entry equal to ± a marker becomes ± that length's symbol, so the symbolic chain is
    the numeric one by construction. Twists become exact multiples of sympy.pi. An entry that is none of
    these (a length entering through a formula) raises rather than freezing a marker into the result, for a spec
    built in Python; a robot file can only name a length as an entry (± name), so its other numbers stay numbers.

    Args:
        robot: Robot name, e.g. "rrp", "elbow", "stanford", "scara", "leg", or a RobotSpec.

    Returns:
        The symbolic chain; `defaults` holds the robot's default lengths.

    Raises:
        UsageError: Unknown robot.
        HexabotError: The robot's table uses a length in a way this module cannot recognise.
    """
    spec = robot if isinstance(robot, robots.RobotSpec) else robots.get(robot)
    # Markers: distinct, irrational-looking, > 0, and unlike 0, 1 or any multiple of π; each a hair from its length's
    # default, so a joint range between lengths, or between a length and a number, keeps its order (markers far from
    # the defaults made a file's valid range lower = "lo", upper = "hi" "lower limit 0.247 exceeds upper limit 0.202").
    primes = _primes(len(spec.lengths))
    markers = {
        name: length.default + math.sqrt(prime) * (1e-6 if length.default else 1e-4)
        for (name, length), prime in zip(spec.lengths.items(), primes, strict=True)
    }
    assumptions = {
        name: ({"nonnegative": True} if length.allow_zero else {"positive": True})
        for name, length in spec.lengths.items()
    }
    fixed = spec.fixed(markers) if spec.fixed is not None else ()
    sc = _from_chain(spec.build(markers), markers, assumptions, strict=spec.source is None, fixed=fixed)
    return dataclasses.replace(sc, defaults={name: length.default for name, length in spec.lengths.items()})


def from_chain(chain: SerialChain, lengths: Mapping[str, float]) -> SymbolicChain:
    """A symbolic chain from a numeric one and the names of the lengths in it.

    Every DH entry (d, a), base or tool translation equal to ± `lengths[name]` becomes ± Symbol(name); other
    entries stay numbers (angles that are k·π/m become exact). Lengths must have distinct non-zero values,
    or an entry could not tell which one it is.

    Args:
        chain: The numeric chain.
        lengths: Symbol name -> the value in [m] it has in `chain`, e.g. {"l1": 0.05, "l2": 0.1, "l3": 0.12}.

    Returns:
        The symbolic chain, with `defaults` = `lengths`.

    Raises:
        UsageError: A name is not a valid symbol name, or two lengths share a value, or a value is 0.
    """
    values = dict(lengths)
    for name, value in values.items():
        if not name.isidentifier():
            raise UsageError(f"length name {name!r} is not a valid symbol name (letters, digits, _)")
        if not (math.isfinite(value) and value != 0.0):
            raise UsageError(f"length '{name}' must be a finite non-zero number to be found in the chain; got {value}")
    names = list(values)
    for i, first in enumerate(names):
        for second in names[i + 1 :]:
            if math.isclose(abs(values[first]), abs(values[second]), rel_tol=MATCH_TOL):
                raise UsageError(
                    f"lengths '{first}' and '{second}' have the same value {values[first]}; "
                    "give them distinct values so that each entry of the chain names one of them"
                )
    assumptions = {name: ({"positive": True} if value > 0 else {"real": True}) for name, value in values.items()}
    return _from_chain(chain, values, assumptions, strict=False)


def transforms(sc: SymbolicChain, simplify: bool = True, max_ops: int | None = None) -> list[sp.Matrix]:
    """Base-frame transforms [T01, ..., T0n, T0tool] (T0i = base · A_1 ⋯ A_i), each a 4x4 matrix.

    Each product is simplified elementwise before the next link multiplies it: sin² + cos² = 1 reduced exactly,
    cos(q2)cos(q3) − sin(q2)sin(q3) written cos(q2 + q3), common factors pulled out (cos(q1)·(l1 + l2 cos(q2)
    + ...)). About 0.1 s for a 3-DOF arm, 0.2 s for the Stanford arm; results are cached on `sc`.

    Args:
        sc: The symbolic chain.
        simplify: False returns the expanded products unsimplified (fast, much longer expressions).
        max_ops: Stop with a UsageError when a simplified T0i has more operations than this (sympy.count_ops of
            its 16 entries): general twists multiply the terms at every joint and the next product, and the
            Jacobian, would take minutes (`kin --symbolic` passes MAX_OPS). None: no limit.

    Returns:
        n + 1 matrices (fresh copies; changing them does not change the cache).
    """
    key = ("transforms", simplify)
    if key not in sc._cache:
        simp = _simplify if simplify else sp.expand
        out: list[sp.ImmutableMatrix] = []
        pose = sc.base
        for i, link in enumerate((*sc.links, sc.tool), start=1):
            pose = sp.ImmutableMatrix(pose * link).applyfunc(simp)
            out.append(pose)
            ops = sum(sp.count_ops(entry) for entry in pose) if max_ops is not None else 0
            if max_ops is not None and ops > max_ops:
                frame = f"T0{i}" if i <= sc.n else "T0tool"
                raise UsageError(
                    f"{sc.name}: the closed form grows too large to simplify in reasonable time: {frame} already has "
                    f"{ops} operations (at most {max_ops}: each joint multiplies the terms, twists other than "
                    "multiples of 90 deg most); use --q for T0n and J at a configuration"
                )
        sc._cache[key] = out
    return [sp.Matrix(t) for t in sc._cache[key]]


def jacobian(sc: SymbolicChain, simplify: bool = True) -> sp.Matrix:
    """Geometric Jacobian (6 x n) of the tool point by the direct method; rows v (linear), then w (angular).

    Revolute column (z_j × (o_tool − o_j), z_j), prismatic column (z_j, 0), where z_j, o_j are the axis and
    origin of the frame the joint acts on (standard DH: frame j-1; modified: frame j), as `SerialChain.jacobian`.

    Args:
        sc: The symbolic chain.
        simplify: Simplify each entry (see `transforms`); False leaves the expanded cross products.

    Returns:
        The Jacobian, 6 x n.
    """
    key = ("jacobian", simplify)
    if key not in sc._cache:
        simp = _simplify if simplify else sp.expand
        frames = [sp.Matrix(sc.base), *transforms(sc, simplify)]  # T00 .. T0n, T0tool
        offset = 0 if sc.convention == "standard" else 1
        p_tool = frames[-1][:3, 3]
        jac = sp.zeros(6, sc.n)
        for j, is_prismatic in enumerate(sc.prismatic):
            frame = frames[j + offset]
            z, o = frame[:3, 2], frame[:3, 3]
            if is_prismatic:
                jac[:3, j] = z
            else:
                jac[:3, j] = z.cross(p_tool - o).applyfunc(simp)
                jac[3:, j] = z
        sc._cache[key] = sp.ImmutableMatrix(jac)
    return sp.Matrix(sc._cache[key])


def jacobian_by_differentiation(sc: SymbolicChain, simplify: bool = True) -> sp.Matrix:
    """Geometric Jacobian (6 x n) by differentiating the tool pose T0tool(q) = [R p; 0 1].

    Linear rows: dp/dq_j. Angular rows: the axial vector (S32, S13, S21) of the skew-symmetric
    S = (dR/dq_j) Rᵀ, computed from the three rows of the products that it needs.

    Args:
        sc: The symbolic chain.
        simplify: Simplify each entry (see `transforms`); without it the angular rows keep sin² + cos² terms.

    Returns:
        The Jacobian, 6 x n; equal to `jacobian(sc)` (shown symbolically in tests/test_symbolic.py).
    """
    key = ("jacobian_by_differentiation", simplify)
    if key not in sc._cache:
        simp = _simplify if simplify else sp.expand
        pose = transforms(sc, simplify)[-1]
        rot, pos = pose[:3, :3], pose[:3, 3]
        jac = sp.zeros(6, sc.n)
        for j, qj in enumerate(sc.q):
            d_rot = rot.diff(qj)
            jac[:3, j] = pos.diff(qj).applyfunc(simp)
            # w_x = S[2, 1] = dR[2, :]·R[1, :], w_y = S[0, 2] = dR[0, :]·R[2, :], w_z = S[1, 0] = dR[1, :]·R[0, :]
            axial = [d_rot[2, :].dot(rot[1, :]), d_rot[0, :].dot(rot[2, :]), d_rot[1, :].dot(rot[0, :])]
            jac[3:, j] = sp.Matrix([simp(w) for w in axial])
        sc._cache[key] = sp.ImmutableMatrix(jac)
    return sp.Matrix(sc._cache[key])


def abbreviated(expr: Any) -> Any:
    """The expression with cos/sin of joint angles written as the reports do: c1, s1, c23 = cos(q2 + q3).

    Only arguments that are a plain sum of distinct revolute joint symbols (q1, q2 + q3, ...) are abbreviated;
    the indices are concatenated in ascending order (c23, s234). Abbreviations are new symbols, for printing.

    Args:
        expr: A sympy expression or matrix.

    Returns:
        The same kind of object with the abbreviations substituted.
    """
    expr = sp.sympify(expr)

    def name(func: type, arg: sp.Expr) -> str | None:
        terms = sp.Add.make_args(arg)
        indices = []
        for term in terms:
            match = _JOINT_SYMBOL.fullmatch(term.name) if isinstance(term, sp.Symbol) else None
            if match is None:
                return None
            indices.append(int(match.group(1)))
        if len(set(indices)) != len(indices):
            return None
        return ("c" if func is sp.cos else "s") + "".join(str(i) for i in sorted(indices))

    replacements = {}
    for node in expr.atoms(sp.cos, sp.sin):
        short = name(type(node), node.args[0])
        if short is not None:
            replacements[node] = sp.Symbol(short, real=True)
    return expr.xreplace(replacements)


def pretty(expr: Any, abbreviate: bool = True, wrap_line: bool = True, num_columns: int | None = None) -> str:
    """2-D plain-text rendering of an expression or matrix (ASCII, so c23 stays "c23" in any console).

    Args:
        expr: A sympy expression or matrix.
        abbreviate: Write cos(q1) as c1, sin(q2 + q3) as s23, as the reports do.
        wrap_line: Wrap lines wider than `num_columns` (sympy's default); False keeps matrices intact.
        num_columns: Width to wrap at; None: sympy's default (80).

    Returns:
        The text, several lines for fractions and matrices.
    """
    shown = abbreviated(expr) if abbreviate else sp.sympify(expr)
    return sp.pretty(shown, use_unicode=False, wrap_line=wrap_line, num_columns=num_columns)


def listing(matrix: Any, name: str, abbreviate: bool = True) -> str:
    """One line per entry, "T11 = c1*c23" (1-based indices), as report 003 lists a 6-DOF arm's T06 and J.

    Args:
        matrix: A sympy matrix.
        name: Prefix of the entry names, e.g. "T06" or "J".
        abbreviate: Write cos(q1) as c1, sin(q2 + q3) as s23.

    Returns:
        The lines joined by newlines; entries too long for `pretty` stay on one line each.
    """
    shown = abbreviated(matrix) if abbreviate else sp.sympify(matrix)
    rows, cols = shown.shape
    sep = "_" if max(rows, cols) > 9 else ""
    return "\n".join(f"{name}{r + 1}{sep}{c + 1} = {sp.sstr(shown[r, c])}" for r in range(rows) for c in range(cols))


def latex(expr: Any, abbreviate: bool = True) -> str:
    """LaTeX of an expression or matrix; abbreviations print as c_{1}, s_{23} (the reports' c_1, s_{23}).

    Args:
        expr: A sympy expression or matrix.
        abbreviate: Write cos(q1) as c_{1}, sin(q2 + q3) as s_{23}.

    Returns:
        LaTeX source without surrounding $ (a matrix is a \\left[\\begin{matrix}...\\end{matrix}\\right]).
    """
    shown = abbreviated(expr) if abbreviate else sp.sympify(expr)
    return sp.latex(shown)


def _simplify(expr: sp.Expr) -> sp.Expr:
    """Exact trig simplification, fast enough for 6 joints (~1 s for the Stanford arm vs ~40 s with trigsimp).

    1. Expand sums of angles and products: a polynomial in the lengths and sin/cos of single joint angles.
    2. Replace sin(x)^2 by 1 - cos(x)^2: the normal form modulo sin² + cos² = 1, so a zero expression gives 0.
    3. Recombine cos(a)cos(b) - sin(a)sin(b) into cos(a + b) etc. (sympy's fu rule TR10i) and pull out common
       factors (c1·(l1 + l2 c2 + l3 c23)), as the reports write them.
    """
    expr = _reduce_pythagorean(sp.expand(sp.expand_trig(expr)))
    return sp.factor_terms(TR10i(expr), sign=False)


def _reduce_pythagorean(expr: sp.Expr) -> sp.Expr:
    """An expanded expression with every sin(x)^k, k >= 2, replaced by (1 - cos(x)^2)^(k // 2) sin(x)^(k % 2)."""

    def is_sin_power(node: sp.Basic) -> bool:
        return node.is_Pow and isinstance(node.base, sp.sin) and node.exp.is_Integer and node.exp >= 2

    def reduce(node: sp.Pow) -> sp.Expr:
        x, k = node.base.args[0], int(node.exp)
        return (1 - sp.cos(x) ** 2) ** (k // 2) * sp.sin(x) ** (k % 2)

    return sp.expand(expr.replace(is_sin_power, reduce))


def _from_chain(
    chain: SerialChain,
    values: Mapping[str, float],
    assumptions: Mapping[str, dict[str, bool]],
    strict: bool,
    fixed: Sequence[Joint] = (),
) -> SymbolicChain:
    """Builds the symbolic chain: names in `values` become symbols wherever ± their value appears. `fixed`: a robot
    file's fixed rows, folded into chain.tool; they are taken out of it and multiplied in as symbolic rows (the
    tool's translation was the sum of their lengths and [tool]'s, matched by no single length: a marker's value was
    printed for l3 + lt)."""
    symbols = {name: sp.Symbol(name, **assumptions[name]) for name in values}
    taken = set(values)
    joint_symbols = []
    for i, joint in enumerate(chain.joints, start=1):
        joint_symbols.append(sp.Symbol(_joint_symbol_name(i, joint.name, joint.prismatic, taken), real=True))

    def length(value: float, where: str) -> sp.Expr:
        if abs(value) < MATCH_TOL:
            return sp.Integer(0)
        for name, marker in values.items():
            for sign in (1, -1):
                if math.isclose(value, sign * marker, rel_tol=MATCH_TOL):
                    return sign * symbols[name]
        if strict:
            raise HexabotError(
                f"{chain.name}: {where} = {value!r} is not ± one of the lengths {', '.join(values)}; "
                "the symbolic chain supports lengths used as DH entries or tool offsets directly"
            )
        return sp.Float(value)

    links = []
    for i, (joint, qi) in enumerate(zip(chain.joints, joint_symbols, strict=True), start=1):
        theta = _angle(joint.theta) + (0 if joint.prismatic else qi)
        d = length(joint.d, f"d of joint {i} ({joint.name})") + (qi if joint.prismatic else 0)
        a = length(joint.a, f"a of joint {i} ({joint.name})")
        links.append(_link(theta, d, a, _angle(joint.alpha), chain.convention))
    return SymbolicChain(
        name=chain.name,
        convention=chain.convention,
        q=tuple(joint_symbols),
        prismatic=tuple(chain.prismatic),
        lengths=symbols,
        defaults=dict(values),
        links=tuple(links),
        base=_fixed_transform(chain.base, length, "base"),
        tool=_tool(chain, fixed, length),
    )


def _tool(chain: SerialChain, fixed: Sequence[Joint], length: Any) -> sp.ImmutableMatrix:
    """The symbolic tool transform: the fixed rows' links (their a and d ± one length or a number each), then the
    file's [tool] (chain.tool with the rows taken out)."""
    rows = np.eye(4)
    links = []
    for k, joint in enumerate(fixed, start=1):
        rows = rows @ joint.transform(0.0, chain.convention)
        d, a = length(joint.d, f"d of fixed row {k}"), length(joint.a, f"a of fixed row {k}")
        links.append(_link(_angle(joint.theta), d, a, _angle(joint.alpha), chain.convention))
    tool = _fixed_transform(np.linalg.solve(rows, chain.tool) if fixed else chain.tool, length, "tool")
    return sp.ImmutableMatrix(functools.reduce(lambda t, link: t * link, links, sp.eye(4)) * tool)


def _joint_symbol_name(index: int, joint_name: str, prismatic: bool, taken: set[str]) -> str:
    """q<i> for a revolute joint; for a prismatic one its own name (d3), else d<i>, else q<i>. Adds it to `taken`."""
    candidates = [f"q{index}"]
    if prismatic:
        misread = _JOINT_SYMBOL.fullmatch(joint_name) or MISREAD_SYMBOL.fullmatch(joint_name)  # c1 read as cos q1
        own = [joint_name] if joint_name.isidentifier() and not misread else []
        candidates = [*own, f"d{index}", f"q{index}"]
    for candidate in candidates:
        if candidate not in taken:
            taken.add(candidate)
            return candidate
    raise UsageError(f"joint {index} ({joint_name}): symbol names {', '.join(candidates)} are all taken by lengths")


def _link(theta: sp.Expr, d: sp.Expr, a: sp.Expr, alpha: sp.Expr, convention: str) -> sp.ImmutableMatrix:
    """Link transform: standard Rz(θ) Tz(d) Tx(a) Rx(α), modified Rx(α) Tx(a) Rz(θ) Tz(d)."""
    ct, st, ca, sa = sp.cos(theta), sp.sin(theta), sp.cos(alpha), sp.sin(alpha)
    if convention == "standard":
        rows = [[ct, -st * ca, st * sa, a * ct], [st, ct * ca, -ct * sa, a * st], [0, sa, ca, d], [0, 0, 0, 1]]
    else:
        rows = [[ct, -st, 0, a], [st * ca, ct * ca, -sa, -d * sa], [st * sa, ct * sa, ca, d * ca], [0, 0, 0, 1]]
    return sp.ImmutableMatrix(rows)


def _angle(value: float) -> sp.Expr:
    """k·π/m exactly when `value` is one (m <= MAX_PI_DENOMINATOR), else a sympy Float."""
    ratio = Fraction(value / math.pi).limit_denominator(MAX_PI_DENOMINATOR)
    if abs(float(ratio) * math.pi - value) <= MATCH_TOL * max(1.0, abs(value)):
        return sp.Rational(ratio.numerator, ratio.denominator) * sp.pi
    return sp.Float(value)


def _unit(value: float) -> sp.Expr:
    """A rotation-matrix entry: 0, ±1, ±1/2, ±√2/2, ±√3/2 exactly when it is one, else a sympy Float."""
    for constant in _UNIT_CONSTANTS:
        for signed in (constant, -constant):
            if abs(float(signed) - value) <= MATCH_TOL:
                return signed
    return sp.Float(value)


def _fixed_transform(matrix: np.ndarray, length: Any, what: str) -> sp.ImmutableMatrix:
    """A constant 4x4 transform: exact rotation entries where possible, translations as lengths."""
    out = sp.eye(4)
    for r in range(3):
        for c in range(3):
            out[r, c] = _unit(float(matrix[r, c]))
        out[r, 3] = length(float(matrix[r, 3]), f"{what}[{r}, 3]")
    return sp.ImmutableMatrix(out)


def _primes(count: int) -> list[int]:
    """The first `count` primes."""
    found: list[int] = []
    candidate = 2
    while len(found) < count:
        if all(candidate % p for p in found):
            found.append(candidate)
        candidate += 1
    return found
