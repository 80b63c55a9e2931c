"""Evaluate constant RAPID expressions: literals, aggregates, arithmetic,
references to constant data, record components and a few pure functions
(Offs, RelTool, OrientZYX and maths).

Anything that depends on the running controller raises NotConstant with the
reason, which the program model reports for the target.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from itertools import repeat
from typing import Any

from rapidfix.rapid import syntax as s
from rapidfix.rapid.instructions import RUNTIME_FUNCTIONS
from rapidfix.rapid.poses import offs, orient_zyx, reltool
from rapidfix.rapid.values import RECORD_FIELDS, Value, ValueShapeError

TypedValue = tuple[Value, "str | None"]
#: an argument as its value is read: (kind, name or None, value node or None)
ArgumentValue = tuple[str, "str | None", "s.Expr | None"]
Lookup = Callable[[str], TypedValue]
Function = Callable[[list[Value], dict], TypedValue]


class NotConstant(Exception):
    """The expression cannot be evaluated before run time; `reason` says why."""

    def __init__(self, reason: str) -> None:
        super().__init__(reason)
        self.reason = reason


def _is_num(value: Value) -> bool:
    return isinstance(value, float)


def _is_pos(value: Value) -> bool:
    return isinstance(value, tuple) and len(value) == 3 and all(map(_is_num, value))


class Evaluator:
    """Evaluates expressions with `lookup(name) -> (value, type)` for data names."""

    def __init__(self, lookup: Lookup,
                 records: dict[str, tuple[tuple[str, str], ...]] | None = None) -> None:
        self.lookup = lookup
        self.records = dict(RECORD_FIELDS)
        if records:
            self.records.update(records)
        #: id(shared tail) -> (the tail, `_scoped_tail` of it): the values of tails whose
        #: arguments hold names (`Offs(p1,0,0,nLift)`), each evaluated once; None (the
        #: default) keeps none, for as long as a name's value may still change
        self.tails: dict[int, tuple] | None = None
        #: while `tails` is kept: id(expression node of a tail) -> (the node, its value or
        #: the NotConstant it raised): the pieces tails share (`,tMill.tframe.trans.x*0,`
        #: among `Offs(p7,tMill.tframe.trans.x*0,p7.trans.x*0,0)` and the next) are read
        #: once, where the tails themselves differ
        self._pieces: dict[int, tuple] = {}

    def value(self, expr: s.Expr) -> Value:
        """The value of `expr`; raises NotConstant."""
        try:
            return self.typed(expr)[0]
        except RecursionError:
            raise NotConstant("expression nested too deeply to evaluate") from None

    def typed(self, expr: s.Expr) -> TypedValue:
        """(value, type name or None) of `expr`; raises NotConstant."""
        kind = type(expr)
        if kind is s.NameRef:  # the most frequent nodes first, by their exact type
            return self.lookup(expr.name)
        if kind is s.Number:
            return expr.value, "num"
        by_type = _TYPED.get(kind)
        if by_type is None:  # a subclass of a node type: as its nearest base
            by_type = next((_TYPED[base] for base in kind.__mro__ if base in _TYPED), None)
            if by_type is None:
                raise NotConstant(f"cannot evaluate {kind.__name__}")
        return by_type(self, expr)

    # ------------------------------------------------------------ operators
    def _unary(self, expr: s.Unary) -> TypedValue:
        value, kind = self.typed(expr.operand)
        if expr.op == "NOT":
            if isinstance(value, bool):
                return not value, "bool"
        elif isinstance(value, float):  # (_is_num, without the call)
            return (-value if expr.op == "-" else value), "num"
        elif _is_pos(value):
            return (tuple(-v for v in value) if expr.op == "-" else value), kind
        raise NotConstant(f"operator {expr.op} on this value is not evaluated")

    def _binary(self, expr: s.Binary) -> TypedValue:
        left, ltype = self.typed(expr.left)
        right, rtype = self.typed(expr.right)
        op = expr.op
        if isinstance(left, float) and isinstance(right, float):  # (_is_num of both)
            return _num_op(op, left, right)
        if isinstance(left, bool) and isinstance(right, bool):
            if op in ("AND", "OR", "XOR", "=", "<>"):
                return {"AND": left and right, "OR": left or right, "XOR": left != right,
                        "=": left == right, "<>": left != right}[op], "bool"
        if isinstance(left, str) and isinstance(right, str):
            if op == "+":
                return left + right, "string"
            if op in ("=", "<>"):
                return (left == right) == (op == "="), "bool"
        if _is_pos(left) and _is_pos(right) and op in ("+", "-"):
            sign = 1.0 if op == "+" else -1.0
            return tuple(a + sign * b for a, b in zip(left, right)), ltype or rtype or "pos"
        if op == "*" and _is_num(left) and _is_pos(right):
            return tuple(left * b for b in right), rtype or "pos"
        if op in ("*", "/") and _is_pos(left) and _is_num(right):
            if op == "/" and right == 0.0:
                raise NotConstant("division by zero")
            return tuple(a * right if op == "*" else a / right for a in left), ltype or "pos"
        raise NotConstant(f"operator {op} on these values is not evaluated")

    # ------------------------------------------------------------ data access
    def _component(self, expr: s.Component) -> TypedValue:
        value, kind = self.typed(expr.base)
        fields = self.records.get(kind or "")
        if fields is None or not isinstance(value, tuple) or len(value) != len(fields):
            raise NotConstant(f"component .{expr.name} of a value of unknown type")
        key = expr.name.lower()
        for (name, field_type), item in zip(fields, value):
            if name == key:
                return item, field_type
        raise NotConstant(f"type {kind} has no component {expr.name}")

    def _index(self, expr: s.Index) -> TypedValue:
        value, kind = self.typed(expr.base)
        for index_expr in expr.indices:
            index = self.value(index_expr)
            if not _is_num(index) or index != int(index):
                raise NotConstant("array index is not a whole number")
            if not isinstance(value, tuple) or not 1 <= index <= len(value):
                raise NotConstant(f"array index {int(index)} out of range")
            value = value[int(index) - 1]
        return value, kind

    # ------------------------------------------------------------ functions
    def _call(self, expr: s.Call, args: list[s.Argument] | None = None) -> TypedValue:
        """The value of a function call; `args` its arguments where they are at hand
        (their values are what counts, not where they stand), else `expr.args`."""
        handler = _handler(expr)
        required, optional, failure = _read_values(self, [
            (a.kind, a.name, a.value) for a in (expr.args if args is None else args)])
        if failure is not None:
            raise NotConstant(failure)
        return _apply(expr, handler, list(required), optional)

    def _lazy_call(self, expr: s.LazyFunctionCall) -> TypedValue:
        """_call of a function call whose further arguments are a shared tail: a tail of
        constants is evaluated once (_tail_values), the first argument every time."""
        head = expr.head
        if head is None or head.value is None:
            return self._call(expr)
        constants, values = _tail_values(expr.tail)
        if constants is None:
            constants = self._scoped_tail(expr.tail, values)
        if constants is None:  # not all literals: its arguments as read, at offset 0
            return self._call(expr, [head, *expr.tail.arguments(0)])
        handler = _handler(expr)
        first = self.value(head.value)  # the first required argument, as _call takes it
        required, optional, failure = constants
        if failure is not None:
            raise NotConstant(failure)
        return _apply(expr, handler, [first, *required], optional)

    def named_call(self, expr: s.LazyFunctionCall, first: Value | NotConstant
                   ) -> TypedValue | None:
        """typed(expr) of a lazily read call whose first argument is a data name and
        whose tail holds only literals (`Offs(p7,0,0,10)`), given that name's value
        `first` (or the NotConstant its lookup raised): the same value, or NotConstant
        with the same reason, in one step. None when the tail is not all literals
        (then use typed).

        A program with a hundred thousand such calls has as many distinct texts: each
        needs its own value, but not the layers of the general route."""
        constants, values = _tail_values(expr.tail)
        if constants is None:
            constants = self._scoped_tail(expr.tail, values)
        if constants is None:
            return None
        handler = _handler(expr)
        if type(first) is NotConstant:
            raise NotConstant(first.reason)
        required, optional, failure = constants
        if failure is not None:
            raise NotConstant(failure)
        return _apply(expr, handler, [first, *required], optional)

    def _scoped_tail(self, tail: s.ArgumentTail, values: list[ArgumentValue]
                     ) -> tuple | None:
        """_tail_values' constants of a shared tail whose arguments hold names (`values`,
        the tail's), evaluated in this evaluator's scope once while `tails` is kept (else
        None): its arguments are read in the order `_call` reads them after the first, so
        a failure gives the reason `_call` gives."""
        kept = self.tails
        if kept is None:
            return None
        known = kept.get(id(tail))
        if known is not None and known[0] is tail:
            return known[1]
        constants = _read_values(self, values, self._piece)
        if len(kept) >= _KEPT_TAILS:
            kept.clear()
        kept[id(tail)] = (tail, constants)
        return constants

    def _piece(self, expr: s.Expr) -> Value:
        """`value` of a node of a kept tail, once per node (`_pieces`)."""
        if type(expr) in s.LEAF_NODES:  # read at once (a name's value is kept by the lookup)
            return self.value(expr)
        pieces = self._pieces
        known = pieces.get(id(expr))
        if known is None or known[0] is not expr:
            try:
                value: Value | NotConstant = self.value(expr)
            except NotConstant as err:
                value = NotConstant(err.reason)  # (without its traceback)
            if len(pieces) >= _KEPT_TAILS:
                pieces.clear()
            known = pieces[id(expr)] = (expr, value)
        value = known[1]
        if type(value) is NotConstant:
            raise NotConstant(value.reason)
        return value


#: the most tails, and their pieces, an evaluator keeps (`Evaluator._scoped_tail`)
_KEPT_TAILS = 4096


def _placeholder(evaluator: Evaluator, expr: s.Placeholder) -> TypedValue:
    raise NotConstant(f"placeholder {expr.text}: code not yet written")


# Evaluator.typed of each node type, by its exact type (one look-up, where a chain of
# isinstance tests took up to a dozen for an operator).
_TYPED: dict[type, Callable[[Evaluator, Any], TypedValue]] = {
    s.NameRef: lambda ev, e: ev.lookup(e.name),
    s.Number: lambda ev, e: (e.value, "num"),
    s.LazyFunctionCall: Evaluator._lazy_call,
    s.Index: Evaluator._index,  # `path{12}`: an array of targets, element by element
    s.NumericAggregate: lambda ev, e: (e.value, None),
    s.Aggregate: lambda ev, e: (tuple([ev.typed(item)[0] for item in e.items]), None),
    s.String: lambda ev, e: (e.value, "string"),
    s.Bool: lambda ev, e: (e.value, "bool"),
    s.Paren: lambda ev, e: ev.typed(e.inner),
    s.Unary: Evaluator._unary,
    s.Binary: Evaluator._binary,
    s.Component: Evaluator._component,
    s.Call: Evaluator._call,
    s.Placeholder: _placeholder,
}


def _handler(expr: s.Call) -> Function:
    """The evaluator of a function call, or NotConstant when it is known only at run time."""
    key = expr.key
    if key in RUNTIME_FUNCTIONS:
        raise NotConstant(f"{expr.name} is read from the controller at run time")
    handler = _FUNCTIONS.get(key)
    if handler is None:
        raise NotConstant(f"function {expr.name} is not evaluated before run time")
    return handler


def _apply(expr: s.Call, handler: Function, required: list[Value], optional: dict
           ) -> TypedValue:
    """`handler`'s value of the arguments; a value it refuses makes the call not constant."""
    try:
        return handler(required, optional)
    except (ValueShapeError, ValueError, TypeError, IndexError, KeyError,
            ZeroDivisionError, OverflowError) as err:
        raise NotConstant(f"{expr.name}: {err}") from None


def _no_names(name: str) -> TypedValue:  # pragma: no cover - only constants are given
    raise NotConstant(f"{name} is not a constant")


_CONSTANT_NODES = (s.Number, s.NumericAggregate, s.String, s.Bool)
# A shared argument tail (see s.LazyFunctionCall) -> (the tail, _tail_values of it); the
# tail is kept so that its id is not reused while the entry lives.
_TAIL_VALUES: dict[int, tuple[object, tuple[tuple | None, list[s.Argument]]]] = {}


def _is_constant(expr: s.Expr | None) -> bool:
    """A literal, a negated one, or no value (a switch): the same value in every scope."""
    while type(expr) is s.Unary:
        expr = expr.operand
    return expr is None or type(expr) in _CONSTANT_NODES


def _tail_values(tail: s.ArgumentTail) -> tuple[tuple | None, list[ArgumentValue]]:
    """(constants, values) of a shared tail. constants: (required values, optional
    values, the reason _call would refuse them or None) of a tail of literals, as _call
    reads them after a call's first argument; None when a tail argument holds a name
    (then evaluated in its scope: `values` are the tail's `values()`, so that they are
    not gathered twice; [] for a tail of literals)."""
    cached = _TAIL_VALUES.get(id(tail))
    if cached is not None and cached[0] is tail:
        return cached[1]
    values = tail.values()
    result: tuple | None = None
    if all(_is_constant(value) for _, _, value in values):
        result = _read_values(Evaluator(_no_names), values)
    if len(_TAIL_VALUES) >= 4096:
        _TAIL_VALUES.clear()
    found = (result, [] if result is not None else values)
    _TAIL_VALUES[id(tail)] = (tail, found)
    return found


def _read_values(evaluator: Evaluator, arguments: list[ArgumentValue],
                 read: Callable[[s.Expr], Value] | None = None) -> tuple:
    """(required values, optional values, None) of a call's arguments (or of those after
    its first) as (kind, name, value node) each, required ones first, then optional
    ones, then a conditional one refused; or ((), {}, the reason of the first that is
    not constant). `read` gives a node's value (default: evaluator.value)."""
    value_of = evaluator.value if read is None else read
    try:
        required = [value_of(value) for kind, _, value in arguments
                    if kind == "required" and value is not None]
        optional = {name.lower(): (value_of(value) if value is not None else True)
                    for kind, name, value in arguments if kind == "optional"}
        if any(kind == "conditional" for kind, _, _ in arguments):
            raise NotConstant("conditional argument is decided at run time")
    except NotConstant as err:
        return (), {}, err.reason
    return tuple(required), optional, None


def _num_op(op: str, a: float, b: float) -> TypedValue:
    if op == "+":
        return a + b, "num"
    if op == "-":
        return a - b, "num"
    if op == "*":
        return a * b, "num"
    if op in ("/", "DIV", "MOD"):
        if b == 0.0:
            raise NotConstant("division by zero")
        if op == "/":
            return a / b, "num"
        quotient = float(math.trunc(a / b))
        return (quotient if op == "DIV" else a - b * quotient), "num"
    comparisons = {"=": a == b, "<>": a != b, "<": a < b, "<=": a <= b, ">": a > b,
                   ">=": a >= b}
    if op in comparisons:
        return comparisons[op], "bool"
    raise NotConstant(f"operator {op} on numbers")


def _nums(args: list[Value], n: int) -> list[float]:
    if len(args) != n or not all(map(isinstance, args, repeat(float))):
        raise ValueError(f"expected {n} numeric arguments")
    return args


def _offs(req: list[Value], opt: dict) -> TypedValue:
    if len(req) != 4:
        raise ValueError("expected Offs(point, dx, dy, dz)")
    return offs(req[0], *_nums(req[1:], 3)), "robtarget"


def _reltool(req: list[Value], opt: dict) -> TypedValue:
    if len(req) != 4:
        raise ValueError("expected RelTool(point, dx, dy, dz [\\Rx] [\\Ry] [\\Rz])")
    angles = [opt.get(k, 0.0) for k in ("rx", "ry", "rz")]
    return reltool(req[0], *_nums(req[1:], 3), *_nums(angles, 3)), "robtarget"


def _orient_zyx(req: list[Value], opt: dict) -> TypedValue:
    ez, ey, ex = _nums(req, 3)
    return orient_zyx(ez, ey, ex), "orient"


def _unary_math(fn: Callable[[float], float]) -> Callable[[list[Value], dict], TypedValue]:
    def handler(req: list[Value], opt: dict) -> TypedValue:
        (x,) = _nums(req, 1)
        return float(fn(x)), "num"
    return handler


def _rounding(fn: Callable[[float], float]) -> Callable[[list[Value], dict], TypedValue]:
    def handler(req: list[Value], opt: dict) -> TypedValue:
        (x,) = _nums(req, 1)
        dec = opt.get("dec", 0.0)
        scale = 10.0 ** dec
        return float(fn(x * scale)) / scale, "num"
    return handler


_FUNCTIONS: dict[str, Function] = {
    "offs": _offs,
    "reltool": _reltool,
    "orientzyx": _orient_zyx,
    "abs": _unary_math(abs),
    "sqrt": _unary_math(math.sqrt),
    "sin": _unary_math(lambda d: math.sin(math.radians(d))),
    "cos": _unary_math(lambda d: math.cos(math.radians(d))),
    "tan": _unary_math(lambda d: math.tan(math.radians(d))),
    "atan2": lambda req, opt: (math.degrees(math.atan2(*_nums(req, 2))), "num"),
    "pow": lambda req, opt: (float(math.pow(*_nums(req, 2))), "num"),
    "round": _rounding(lambda v: math.floor(v + 0.5) if v >= 0 else -math.floor(-v + 0.5)),
    "trunc": _rounding(math.trunc),
}
