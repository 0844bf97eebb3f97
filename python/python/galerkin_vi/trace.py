"""Lagrangians written as Python functions, compiled once into the expression tape.

``from_function(L, coordinates)`` calls ``L(q, v)`` (or ``L(q, v, t)``) **once**, with tracer
objects in place of numbers. Each operation on a tracer records itself, so the call returns
the Lagrangian as an expression in the grammar of :class:`galerkin_vi.systems.Expression`
(``+ - * / ^``, ``sin cos tan exp log sqrt abs pow atan2 sinh cosh tanh``), which is then
parsed and compiled exactly as a hand-written expression string: the integrator never calls
Python, and the traced system is as fast as the string (the tapes are identical).

Use Python arithmetic (``+ - * / **``, unary minus, ``abs``) and the functions of this module
(``sin``, ``cos``, ``tan``, ``exp``, ``log``, ``sqrt``, ``atan2``, ``sinh``, ``cosh``,
``tanh``, ``pow``; re-exported as ``galerkin_vi.sin`` …; numpy's ufuncs of the same names work
too). They also accept plain numbers and arrays (then they are numpy's).

What a single trace cannot record is refused with a ``TypeError`` that says why: branching
on a traced value (``if``, ``while``, ``and``/``or``, comparisons), turning it into a float
(``float(x)``, ``math.sin(x)``: use ``galerkin_vi.sin``), and numpy functions without a
counterpart in the grammar.

``from_sympy(expr, coordinates, velocities)`` converts a sympy expression the same way.
"""

from __future__ import annotations

import inspect
import math
import numbers

import numpy as np

from ._native import Expression, ExpressionError, NonFiniteError

__all__ = [
    "Traced",
    "atan2",
    "cos",
    "cosh",
    "exp",
    "from_function",
    "from_sympy",
    "log",
    "pow",
    "sin",
    "sinh",
    "sqrt",
    "tan",
    "tanh",
]

# Binding strength of the printed forms: a sum, a product, a negation, a power, an atom.
_SUM, _PRODUCT, _NEGATION, _POWER, _ATOM = 1, 2, 3, 4, 5

_FUNCTIONS = ("sin", "cos", "tan", "exp", "log", "sqrt", "abs", "sinh", "cosh", "tanh")

_FLOAT_HINT = (
    "use gv.sin, gv.cos, gv.exp, gv.log, gv.sqrt, ... (the functions of galerkin_vi, "
    "imported as gv) or numpy's ufuncs instead of the math module"
)


def _number_text(x: float) -> str:
    """A finite non-negative float as a literal of the grammar, read back bit for bit."""
    if x.is_integer() and x < 1e15:
        return str(int(x))
    return repr(float(x)).replace("e+", "e")


class Traced:
    """A value recorded while a Lagrangian is traced: an expression of the grammar of
    :class:`galerkin_vi.systems.Expression` (``text``) and how strongly it binds.

    Arithmetic with numbers and other traced values gives traced values; branching on one or
    converting it to a float raises ``TypeError``."""

    __slots__ = ("text", "binding")
    __array_priority__ = 1000

    def __init__(self, text: str, binding: int = _ATOM):
        self.text = text
        self.binding = binding

    def __repr__(self) -> str:
        return f"Traced({self.text!r})"

    # -- printing ----------------------------------------------------------------------
    def _as_operand(self, at_least: int) -> str:
        return self.text if self.binding >= at_least else f"({self.text})"

    @staticmethod
    def of(x) -> "Traced":
        """``x`` as a traced value: a traced value itself, or a finite real number."""
        if isinstance(x, Traced):
            return x
        if isinstance(x, (bool, np.bool_)):
            raise TypeError(
                f"a boolean ({x!r}) in a traced Lagrangian: comparisons and tests cannot be "
                "traced; write L without branching"
            )
        if isinstance(x, numbers.Real) or (isinstance(x, np.ndarray) and x.shape == ()):
            value = float(x)
            if not math.isfinite(value):
                raise NonFiniteError(f"a traced Lagrangian contains the number {value}")
            if value < 0 or (value == 0 and math.copysign(1.0, value) < 0):
                return Traced("-" + _number_text(-value), _NEGATION)
            return Traced(_number_text(value))
        raise TypeError(
            f"cannot trace an operation with {type(x).__name__} {x!r}: a traced Lagrangian "
            "combines q, v, t and the parameters with numbers, the arithmetic operators and "
            "the functions of galerkin_vi (sin, cos, exp, ...)"
        )

    def _binary(self, op: str, other, reflected: bool = False) -> "Traced":
        a, b = Traced.of(self), Traced.of(other)
        if reflected:
            a, b = b, a
        if op in "+-":
            strength = _SUM
        else:
            strength = _PRODUCT
        # Left operands keep their own grouping at equal strength (left-associative); right
        # operands at equal strength are grouped, so the tree is Python's. A negation binds as
        # in Python (-a*b is (-a)*b, a*-b is a*(-b), -a^2 is -(a^2)) and needs no grouping.
        left = a._as_operand(strength)
        right = b._as_operand(strength + 1)
        space = " " if strength == _SUM else ""
        return Traced(f"{left}{space}{op}{space}{right}", strength)

    def __add__(self, other):
        return self._binary("+", other)

    def __radd__(self, other):
        return self._binary("+", other, reflected=True)

    def __sub__(self, other):
        return self._binary("-", other)

    def __rsub__(self, other):
        return self._binary("-", other, reflected=True)

    def __mul__(self, other):
        return self._binary("*", other)

    def __rmul__(self, other):
        return self._binary("*", other, reflected=True)

    def __truediv__(self, other):
        return self._binary("/", other)

    def __rtruediv__(self, other):
        return self._binary("/", other, reflected=True)

    def __pow__(self, other, modulo=None):
        if modulo is not None:
            raise TypeError("pow(x, y, modulo) cannot be traced")
        return _power(self, other)

    def __rpow__(self, other):
        return _power(other, self)

    def __neg__(self):
        return Traced("-" + self._as_operand(_POWER), _NEGATION)

    def __pos__(self):
        return self

    def __abs__(self):
        return _call("abs", self)

    # -- what a single trace cannot record ---------------------------------------------
    def _refuse_branch(self, *_args):
        raise TypeError(
            f"the Lagrangian is traced once, with symbols in place of numbers, so a traced "
            f"value ({self.text}) has no truth value: Python's if, while, and, or, not and "
            "comparisons cannot depend on q, v, t or the parameters. Write L without "
            "branching (abs(x) or gv.sqrt(x**2) instead of a test), or as an "
            "expression string"
        )

    __bool__ = _refuse_branch
    __lt__ = __le__ = __gt__ = __ge__ = _refuse_branch
    __eq__ = __ne__ = _refuse_branch
    __hash__ = None

    def _refuse_number(self, *_args):
        raise TypeError(
            f"a traced value ({self.text}) is a symbol, not a number, so it cannot become a "
            f"float: {_FLOAT_HINT}"
        )

    __float__ = __int__ = __index__ = __complex__ = __round__ = _refuse_number
    __floor__ = __ceil__ = __trunc__ = _refuse_number

    def __floordiv__(self, other):
        raise TypeError("// (floor division) cannot be traced: the grammar has no floor")

    __rfloordiv__ = __mod__ = __rmod__ = __floordiv__

    def __iter__(self):
        raise TypeError(f"a traced value ({self.text}) is a scalar; it cannot be iterated")

    # -- numpy: ufuncs with a counterpart in the grammar -------------------------------
    def __array_ufunc__(self, ufunc, method, *inputs, **kwargs):
        if method != "__call__" or kwargs:
            raise TypeError(f"numpy.{ufunc.__name__}.{method} cannot be traced")
        name = ufunc.__name__
        if name in _UFUNCS:
            return _UFUNCS[name](*inputs)
        raise TypeError(
            f"numpy.{name} has no counterpart in the expression grammar and cannot be traced; "
            "the traceable functions are + - * / ** abs and galerkin_vi.sin, cos, tan, exp, "
            "log, sqrt, atan2, sinh, cosh, tanh, pow"
        )


def _call(name: str, *args) -> Traced:
    texts = ", ".join(Traced.of(a).text for a in args)
    return Traced(f"{name}({texts})")


def _method(name: str):
    def method(self):
        return _call(name, self)

    method.__name__ = name
    method.__doc__ = f"The traced {name}(x) (numpy calls it for object arrays of traced values)."
    return method


# numpy applies np.sin, ... to object arrays (np.sin(np.array(q))) by calling these methods.
for _name in ("sin", "cos", "tan", "exp", "log", "sqrt", "sinh", "cosh", "tanh"):
    setattr(Traced, _name, _method(_name))


def _power(base, exponent) -> Traced:
    a, b = Traced.of(base), Traced.of(exponent)
    # ^ is right-associative and binds tighter than negation: group everything but atoms.
    return Traced(f"{a._as_operand(_ATOM)}^{b._as_operand(_ATOM)}", _POWER)


def _traced(*args) -> bool:
    return any(isinstance(a, Traced) for a in args)


def _unary(name: str, numpy_function):
    def function(x):
        if isinstance(x, Traced):
            return _call(name, x)
        if isinstance(x, np.ndarray) and x.dtype == object:
            return np.vectorize(function, otypes=[object])(x)
        return numpy_function(x)

    function.__name__ = name
    function.__qualname__ = name
    function.__doc__ = (
        f"{name}(x): numpy.{numpy_function.__name__} of a number or array; of a traced value, "
        f"the traced {name}(x)."
    )
    return function


sin = _unary("sin", np.sin)
cos = _unary("cos", np.cos)
tan = _unary("tan", np.tan)
exp = _unary("exp", np.exp)
log = _unary("log", np.log)
sqrt = _unary("sqrt", np.sqrt)
sinh = _unary("sinh", np.sinh)
cosh = _unary("cosh", np.cosh)
tanh = _unary("tanh", np.tanh)


def atan2(y, x):
    """atan2(y, x): the angle of the point (x, y); numpy.arctan2 of numbers or arrays, the
    traced atan2 of traced values."""
    if _traced(y, x):
        return _call("atan2", y, x)
    return np.arctan2(y, x)


def pow(x, y):  # noqa: A001 (the grammar's name)
    """pow(x, y) = x**y, traced or numeric."""
    if _traced(x, y):
        return _power(x, y)
    return np.power(x, y)


_UFUNCS = {
    "add": lambda a, b: Traced.of(a) + b,
    "subtract": lambda a, b: Traced.of(a) - b,
    "multiply": lambda a, b: Traced.of(a) * b,
    "true_divide": lambda a, b: Traced.of(a) / b,
    "divide": lambda a, b: Traced.of(a) / b,
    "power": _power,
    "float_power": _power,
    "negative": lambda a: -Traced.of(a),
    "positive": lambda a: Traced.of(a),
    "absolute": lambda a: _call("abs", a),
    "square": lambda a: _power(a, 2),
    "sin": sin,
    "cos": cos,
    "tan": tan,
    "exp": exp,
    "log": log,
    "sqrt": sqrt,
    "sinh": sinh,
    "cosh": cosh,
    "tanh": tanh,
    "arctan2": lambda y, x: _call("atan2", y, x),
}


def _names(coordinates) -> list[str]:
    if isinstance(coordinates, numbers.Integral) and not isinstance(coordinates, bool):
        if coordinates < 1:
            raise ExpressionError(f"coordinates = {coordinates}: at least one is needed")
        return [f"q{i}" for i in range(int(coordinates))]
    if isinstance(coordinates, str):
        return [coordinates]
    return [str(c) for c in coordinates]


def _trace(function, names, parameters, what):
    """Call ``function(q, v[, t], **parameters)`` once with traced values."""
    q = tuple(Traced(n) for n in names)
    v = tuple(Traced(f"{n}_dot") for n in names)
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):
        signature = None
    if signature is None:
        return function(q, v, **{name: Traced(name) for name in parameters})
    kinds = [p.kind for p in signature.parameters.values()]
    named = {
        p.name
        for p in signature.parameters.values()
        if p.kind in (p.POSITIONAL_OR_KEYWORD, p.KEYWORD_ONLY)
    }
    # Each parameter the function takes by name (all of them with **kwargs); one it does not
    # take is simply not read.
    takes_any = inspect.Parameter.VAR_KEYWORD in kinds
    kwargs = {name: Traced(name) for name in parameters if takes_any or name in named}
    positional = sum(
        p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) and p.name not in parameters
        for p in signature.parameters.values()
    )
    if "t" in named and "t" not in parameters:
        kwargs["t"] = Traced("t")
        return function(q, v, **kwargs)
    if positional >= 3 or inspect.Parameter.VAR_POSITIONAL in kinds:
        return function(q, v, Traced("t"), **kwargs)
    return function(q, v, **kwargs)


def from_function(lagrangian, coordinates, parameters=None, force=None) -> Expression:
    """Compile a Python function ``L(q, v)`` (or ``L(q, v, t)``) into an
    :class:`~galerkin_vi.systems.Expression` by tracing it once.

    ``coordinates``: the coordinate names (``["x", "y"]``; the velocities are ``x_dot``, ...)
    or their number D (names ``q0``, ``q1``, ...). ``q`` and ``v`` are tuples of traced
    values, ``t`` (passed when L takes a third argument or one named ``t``) the time.
    ``parameters``: a dict name → value; each is passed to L (and to a force function) as a
    keyword argument of that name if it takes one, and stays a named parameter of the
    expression. ``force``: None, a list of expression
    strings, or a function ``f(q, v)`` / ``f(q, v, t)`` returning one value per coordinate,
    traced the same way.

    The result is an ordinary ``Expression`` (its ``lagrangian`` is the traced text), usable
    wherever one is. Errors: ``TypeError`` for what a single trace cannot record (a branch
    on a traced value, ``math.sin`` of one, an unsupported numpy function); the
    ``ExpressionError`` of the expression itself (L not reading every velocity, not regular).
    """
    if not callable(lagrangian):
        raise TypeError(
            f"lagrangian: expected a function L(q, v) or L(q, v, t), got "
            f"{type(lagrangian).__name__}"
        )
    names = _names(coordinates)
    parameters = dict(parameters or {})
    result = _trace(lagrangian, names, parameters, "L")
    text = _scalar_text(result, "L")
    forces = _force_texts(force, names, parameters)
    return Expression(text, names, parameters or None, forces)


def _scalar_text(result, what: str) -> str:
    if isinstance(result, np.ndarray) and result.shape == ():
        result = result[()]
    if isinstance(result, (Traced, numbers.Real)) and not isinstance(result, bool):
        return Traced.of(result).text
    raise TypeError(
        f"{what} must return a scalar expression (a traced value or a number), got "
        f"{type(result).__name__}"
    )


def _force_texts(force, names, parameters):
    if force is None:
        return None
    if callable(force):
        result = _trace(force, names, parameters, "force")
        try:
            items = list(result)
        except TypeError:
            items = [result]
        if len(items) != len(names):
            raise ExpressionError(
                f"force: expected one value per coordinate ({len(names)}), got {len(items)}"
            )
        return [_scalar_text(f, "force") for f in items]
    if isinstance(force, str):
        return [force]
    return [f if isinstance(f, str) else _scalar_text(f, "force") for f in force]


# -- sympy ---------------------------------------------------------------------------------

_SYMPY_FUNCTIONS = {
    "sin": "sin",
    "cos": "cos",
    "tan": "tan",
    "exp": "exp",
    "log": "log",
    "Abs": "abs",
    "sinh": "sinh",
    "cosh": "cosh",
    "tanh": "tanh",
    "atan2": "atan2",
}


def _from_sympy_node(e, table):
    import sympy

    if e in table:
        return table[e]
    if e is sympy.pi:
        return Traced("pi")
    if e is sympy.E:
        return _call("exp", 1)
    if e.is_Number:
        if not e.is_real or not e.is_finite:
            raise ExpressionError(f"sympy: {e} is not a finite real number")
        return Traced.of(float(e))
    if e.is_Symbol or isinstance(e, (sympy.Derivative, sympy.core.function.AppliedUndef)):
        known = ", ".join(str(k) for k in table)
        raise ExpressionError(
            f"sympy: the symbol {e} is not a coordinate, velocity, parameter or t "
            f"(known: {known})"
        )
    args = [_from_sympy_node(a, table) for a in e.args]
    if e.is_Add:
        total = args[0]
        for a in args[1:]:
            total = total + a
        return total
    if e.is_Mul:
        numerator, denominator = [], []
        for factor, a in zip(e.args, args):
            if factor.is_Pow and factor.exp.is_Number and factor.exp < 0:
                denominator.append(_from_sympy_node(factor.base ** (-factor.exp), table))
            else:
                numerator.append(a)
        product = numerator[0] if numerator else Traced.of(1)
        for a in numerator[1:]:
            product = product * a
        for a in denominator:
            product = product / a
        return product
    if e.is_Pow:
        base, exponent = e.args
        if exponent == sympy.Rational(1, 2):
            return _call("sqrt", args[0])
        if exponent == sympy.Rational(-1, 2):
            return 1 / _call("sqrt", args[0])
        if exponent.is_Integer and exponent < 0:
            return 1 / _power(args[0], Traced.of(int(-exponent)))
        return _power(args[0], args[1])
    name = type(e).__name__
    if name in _SYMPY_FUNCTIONS:
        return _call(_SYMPY_FUNCTIONS[name], *args)
    raise ExpressionError(
        f"sympy: {name} ({e}) has no counterpart in the expression grammar; supported: + - * "
        f"/ ^, {', '.join(sorted(set(_SYMPY_FUNCTIONS.values()) | {'sqrt'}))}, pi, E"
    )


def _sympy_name(x) -> str:
    import sympy

    if isinstance(x, str):
        return x
    if isinstance(x, sympy.Symbol):
        return x.name
    if isinstance(x, sympy.core.function.AppliedUndef):
        return type(x).__name__
    raise ExpressionError(f"sympy: a coordinate must be a Symbol or a function of t, got {x}")


def from_sympy(lagrangian, coordinates, velocities, parameters=None, t=None, force=None):
    """Compile a sympy expression into an :class:`~galerkin_vi.systems.Expression`.

    ``coordinates``: sympy Symbols (or functions of time, ``x(t)``); ``velocities``: the
    Symbols (or ``Derivative(x(t), t)``) standing for their velocities, in the same order;
    ``parameters``: a dict Symbol (or name) → value; ``t``: the time Symbol if L reads it;
    ``force``: None or a list of sympy expressions, one per coordinate. The expression is
    printed into the grammar through the tracer of :func:`from_function` (``+ - * / ^``,
    ``sin cos tan exp log sqrt Abs atan2 sinh cosh tanh``, ``pi``, ``E``); anything else,
    and a symbol that is none of the above, is an ``ExpressionError``. Needs sympy.
    """
    try:
        import sympy
    except ImportError as e:  # pragma: no cover - depends on the environment
        raise ImportError("from_sympy needs sympy (pip install sympy)") from e
    coordinates = list(coordinates)
    velocities = list(velocities)
    if len(coordinates) != len(velocities):
        raise ExpressionError(
            f"sympy: {len(coordinates)} coordinates but {len(velocities)} velocities"
        )
    names = [_sympy_name(c) for c in coordinates]
    table = {}
    for c, v, n in zip(coordinates, velocities, names):
        table[sympy.sympify(c)] = Traced(n)
        table[sympy.sympify(v)] = Traced(f"{n}_dot")
    values = {}
    for key, value in (parameters or {}).items():
        name = _sympy_name(key)
        values[name] = float(value)
        table[sympy.Symbol(name) if isinstance(key, str) else key] = Traced(name)
    if t is not None:
        table[sympy.sympify(t)] = Traced("t")
    text = _from_sympy_node(sympy.sympify(lagrangian), table).text
    forces = None
    if force is not None:
        forces = [_from_sympy_node(sympy.sympify(f), table).text for f in force]
    return Expression(text, names, values or None, forces)
