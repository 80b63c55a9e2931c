"""Build the program model from a syntax tree in a few linear passes.

1. collect modules, records, routines and declarations with their scopes;
2. walk every routine's statements once: note where data is written
   (assignments, INOUT/VAR arguments, SearchL's SearchPoint, ...) and collect
   the motion instructions with their loop depth;
3. evaluate declarations (memoised, in dependency order) and the operands of
   every motion instruction, recording why a value is not static.

A CAM program has a hundred thousand of each, so the common cases take short
ways that give exactly what the general ones would: an all-numeric constant of
its declared shape is taken as read, each data name is looked up once per
routine and type, and the motions are made in one loop.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from rapidfix.rapid import syntax as s
from rapidfix.rapid.evaluate import Evaluator, NotConstant, TypedValue
from rapidfix.rapid.instructions import WRITING_PROCEDURES, MotionSpec, motion_spec
from rapidfix.rapid.program import (
    Declaration,
    ModuleInfo,
    MotionInstruction,
    Operand,
    Program,
    RoutineInfo,
)
from rapidfix.rapid.scope import find_visible
from rapidfix.rapid.source import SourceText
from rapidfix.rapid.system_data import SYSTEM_DATA
from rapidfix.rapid.values import ValueShapeError, fits_type, typed_value

#: the scope of a name that has none (no routine, or nothing declared there)
_NONE: dict[str, object] = {}
# a shared tail a routine takes from its module's routines (ModelBuilder._module_tail)
_MODULE_TAIL = object()
# what may be a name in RAPID text (rapid.lark's NAME, and digits and numbers' letters)
_WORDS = re.compile("[A-Za-z0-9_\u00c0-\u00d6\u00d8-\u00f6\u00f8-\u00ff]+")

# role of a required parameter -> the data type it takes
_ROLE_TYPES = {
    "topoint": "robtarget",
    "cirpoint": "robtarget",
    "searchpoint": "robtarget",
    "tojointpos": "jointtarget",
    "speed": "speeddata",
    "zone": "zonedata",
    "tool": "tooldata",
    "wobj": "wobjdata",
    "tload": "loaddata",
}


@dataclass(frozen=True)
class _Param:
    parameter: s.Parameter
    routine: str


@dataclass(frozen=True)
class _LoopVariable:
    name: str


@dataclass(frozen=True)
class _Write:
    offset: int
    how: str
    in_loop: bool


# per required position of an instruction: (parameter key, type hint, operand cache)
_Layout = tuple[tuple[str, "str | None", dict], ...]


class _SharedTail:
    """The operands after the targets that calls with the same tail share within a
    routine: their Operands are made (around each call's own argument nodes) only
    when a move's `arguments` or `optional` are asked for."""

    __slots__ = ("entries", "head_keys", "head_of_target", "target_of_head")

    def __init__(self, head_keys: tuple[str, ...], target_keys: tuple[str, ...],
                 entries: tuple[tuple[bool, str, Operand | None], ...]) -> None:
        self.head_keys = head_keys  # the parameter of each leading argument (a target)
        order = [key for key in target_keys if key in head_keys]
        self.target_of_head = tuple(order.index(key) for key in head_keys)
        self.head_of_target = tuple(head_keys.index(key) for key in order)
        # per tail argument: (optional, key, operand of the first call, or None where
        # each call has its own number)
        self.entries = entries

    def operands(self, motion: MotionInstruction) -> tuple[dict[str, Operand],
                                                          dict[str, Operand]]:
        targets = motion.targets
        arguments = {key: targets[i] for key, i in zip(self.head_keys, self.target_of_head)}
        optional: dict[str, Operand] = {}
        for (is_optional, key, first), arg in zip(self.entries, motion.syntax.shared_args()):
            if first is None:  # a number of the call's own (`_own_number`)
                (optional if is_optional else arguments)[key] = Operand(
                    arg, motion.source, None, "expression", None, "num", arg.value.value,
                    True, None, None)
                continue
            (optional if is_optional else arguments)[key] = Operand(
                arg, first.source, first.given_text, first.form, first.name, first.type_name,
                first.value, first.static, first.reason, first.declaration)
        return arguments, optional


def _own_number(kind: str, option: str | None, node: s.Expr | None) -> bool:
    """Whether an argument is an optional one whose value is a number literal and whose
    parameter takes no data of a role (`\\ID:=10`, `\\V:=120`): its operand is the
    number's own (what `ModelBuilder._operand` makes of it), so calls that differ there
    can share the rest."""
    return (kind == "optional" and type(node) is s.Number
            and _ROLE_TYPES.get(option.lower() if option else "") is None)


def _lead_key(lead: s.ArgumentTail) -> object:
    """What the operands of a call's lead (its optional arguments before its target)
    depend on: the lead itself, or, where its only values are numbers of its own
    (`MoveL \\ID:=10, p10, ...`: a MultiMove program numbers every move), the names of
    its arguments."""
    values = lead.values()
    if not all(node is None or _own_number(kind, option, node)
               for kind, option, node in values):
        return id(lead)
    return tuple((kind, option.lower() if option else None, node is None)
                 for kind, option, node in values)


def _root_name(expr: s.Expr | None) -> s.NameRef | None:
    while isinstance(expr, (s.Index, s.Component)):
        expr = expr.base
    return expr if isinstance(expr, s.NameRef) else None


class ModelBuilder:
    """Builds a Program from source text and its syntax tree (see the module doc)."""

    def __init__(self, source: SourceText, kept_bytes: bytes | None,
                 tree: s.SourceFile) -> None:
        self.source = source
        self.program = Program(source, kept_bytes, tree)
        self.module_names: dict[str, dict[str, Declaration]] = {}
        self.global_names: dict[str, Declaration] = {}
        self.routine_names: dict[tuple[str, str], dict[str, object]] = {}
        self.user_routines: dict[str, s.Routine] = {}
        self.records: dict[str, tuple[tuple[str, str], ...]] = {}
        self.writes: dict[int, list[_Write]] = {}
        self.state: dict[int, bool] = {}  # False while evaluating, True when done
        self.evaluators: dict[tuple[str, str | None], Evaluator] = {}
        self.settled = False  # True once every declaration is resolved (pass 3)
        # (module, routine, type hint) -> data name as spelt -> what an Operand of it holds
        self.name_operands: dict[tuple[str, str, str | None], dict[str, tuple]] = {}
        # (module, routine, type hint) -> operand text -> _operand_fields of it
        self.operand_texts: dict[tuple[str, str | None, str | None], dict[str, tuple]] = {}
        self.pending: list[tuple[s.ProcedureCall, MotionSpec, str, str, bool] | None] = []
        # procedure name as spelt -> (motion spec, positions and names it writes into)
        self.call_kinds: dict[str, tuple[MotionSpec | None, set[int], set[str]]] = {}
        self.module_names_as_spelt: dict[str, str] = {}

    # ------------------------------------------------------------ pass 1
    def _declaration(self, decl: s.DataDecl, module: str, routine: str | None) -> Declaration:
        return Declaration(decl.name, decl.type_name, decl.storage, module, routine, decl,
                           self.source, decl.local, decl.task)

    def _collect(self) -> None:
        program = self.program
        for module in program.syntax.modules:
            mkey = module.name.lower()
            names = self.module_names.setdefault(mkey, {})
            last_decl_end = module.header_end
            declarations, global_names = program.declarations, self.global_names
            source = self.source
            for item in module.items:
                if type(item) is s.DataDecl:
                    decl = Declaration(item.name, item.type_name, item.storage, module.name, None,
                                       item, source, item.local, item.task)
                    declarations.append(decl)
                    key = item.name.lower()
                    if key not in names:
                        names[key] = decl
                    if not item.local and key not in global_names:
                        global_names[key] = decl
                    last_decl_end = item.end
                elif isinstance(item, s.RecordDecl):
                    self.records[item.name.lower()] = tuple(
                        (f.name.lower(), f.type_name.lower()) for f in item.fields)
                elif isinstance(item, s.Routine):
                    self._collect_routine(item, module.name)
            program.modules.append(ModuleInfo(
                module.name, module.attributes, program.span(module.start, module.end),
                module.header_end, last_decl_end, module))

    def _collect_routine(self, routine: s.Routine, module: str) -> None:
        program = self.program
        program.routines.append(RoutineInfo(
            routine.name, routine.kind, module, program.span(routine.start, routine.end),
            routine))
        self.user_routines.setdefault(routine.key, routine)
        scope: dict[str, object] = {}
        for param in routine.parameters:
            scope[param.key] = _Param(param, routine.name)
        for item in routine.data:
            decl = self._declaration(item, module, routine.name)
            program.declarations.append(decl)
            scope[decl.key] = decl
        self.routine_names[(module.lower(), routine.key)] = scope

    # ------------------------------------------------------------ names
    def _find(self, key: str, module: str, routine: str | None) -> object | None:
        routine_scope = _NONE if routine is None else self.routine_names.get((module, routine),
                                                                              _NONE)
        return find_visible(key, routine_scope, self.module_names.get(module, _NONE),
                            self.global_names)

    def _lookup(self, name: str, module: str, routine: str | None) -> TypedValue:
        found = self._find(name.lower(), module, routine)
        if isinstance(found, Declaration):
            self._resolve(found)
            if found.static and found.value is not None:
                return found.value, found.type_key
            raise NotConstant(f"{found.name}: {found.reason}")
        if isinstance(found, _Param):
            raise NotConstant(f"{name} is a parameter of routine {found.routine}")
        if isinstance(found, _LoopVariable):
            raise NotConstant(f"{name} is a FOR loop variable")
        system = SYSTEM_DATA.get(name.lower())
        if system is not None:
            return system
        raise NotConstant(f"{name} is not declared in this file")

    def _evaluator(self, module: str, routine: str | None) -> Evaluator:
        key = (module, routine)
        evaluator = self.evaluators.get(key)
        if evaluator is None:
            known: dict[str, TypedValue | NotConstant] = {}

            def lookup(name: str) -> TypedValue:
                # once every declaration is resolved, a name's value no longer changes
                # (before, a declaration may be in the middle of its own evaluation)
                found = known.get(name)
                if found is None:
                    try:
                        found = self._lookup(name, module, routine)
                    except NotConstant as err:
                        # kept without its traceback: that holds the frames down to this
                        # one, and with them the builder and its program, in a cycle only
                        # the collector frees (never, once a large build is frozen)
                        found = NotConstant(err.reason)
                    if self.settled:
                        known[name] = found
                if type(found) is NotConstant:
                    raise NotConstant(found.reason)
                return found
            evaluator = self.evaluators[key] = Evaluator(lookup, self.records)
            if self.settled:  # names keep their values now: a tail's are worth keeping
                evaluator.tails = {}
        return evaluator

    # ------------------------------------------------------------ pass 2
    def _note_write(self, expr: s.Expr | None, module: str, routine: str, how: str,
                    offset: int, in_loop: bool) -> None:
        root = _root_name(expr)
        if root is None:
            return
        found = self._find(root.key, module, routine)
        if isinstance(found, Declaration) and found.storage != "CONST":
            self.writes.setdefault(id(found), []).append(_Write(offset, how, in_loop))

    def _written_positions(self, call: s.ProcedureCall) -> tuple[set[int], set[str]]:
        """Required positions and optional names a procedure call may write into."""
        positions = set(WRITING_PROCEDURES.get(call.key, ()))
        names: set[str] = set()
        user = self.user_routines.get(call.key)
        if user is not None and user.kind == "PROC":
            required = [p for p in user.parameters if not p.optional]
            for i, param in enumerate(required):
                if param.access in ("VAR", "PERS", "INOUT"):
                    positions.add(i)
            names = {p.key for p in user.parameters
                     if p.optional and p.access in ("VAR", "PERS", "INOUT")}
        return positions, names

    def _scan_routine(self, routine: s.Routine, module: str) -> None:
        rkey = routine.key
        scope = self.routine_names[(module, rkey)]
        bodies = [routine.body] + [h.body for h in routine.handlers]
        for body in bodies:
            for statement, loops in s.walk_statements(body):
                kind = type(statement)
                if kind is s.LazyCall or kind is s.ProcedureCall:
                    self._scan_call(statement, module, routine, loops > 0)
                elif kind is s.Assignment:
                    self._note_write(statement.target, module, rkey,
                                     "assigned", statement.start, loops > 0)
                elif kind is s.For:
                    scope.setdefault(statement.variable.lower(),
                                     _LoopVariable(statement.variable))

    def _scan_call(self, call: s.ProcedureCall, module: str, routine: s.Routine,
                   in_loop: bool) -> None:
        # a CAM program calls the same few procedures on every line: look each up once
        known = self.call_kinds.get(call.name)
        if known is None:
            known = self.call_kinds[call.name] = (
                motion_spec(call.name), *self._written_positions(call))
        spec, positions, names = known
        if spec is not None:
            self.pending.append((call, spec, module, routine.name, in_loop))
        else:
            self.program.other_calls.append((call, routine))
        if not positions and not names:
            return
        how = f"written by {call.name}"
        index = 0
        for arg in call.args:
            if arg.kind == "required":
                if index in positions:
                    self._note_write(arg.value, module, routine.key, how, call.start, in_loop)
                index += 1
            elif arg.key in names:
                self._note_write(arg.value, module, routine.key, how, call.start, in_loop)

    # ------------------------------------------------------------ pass 3
    def _resolve(self, decl: Declaration) -> None:
        if self.settled:  # every declaration is resolved
            return
        done = self.state.get(id(decl))
        if done:
            return
        if done is False:
            decl.static, decl.reason = False, f"{decl.name} is defined in terms of itself"
            return
        self.state[id(decl)] = False
        try:
            self._evaluate_declaration(decl)
        finally:
            self.state[id(decl)] = True

    def _evaluate_declaration(self, decl: Declaration) -> None:
        syntax = decl.syntax
        if not syntax.dims and type(syntax.init) is s.NumericAggregate:
            # the bulk of a CAM program: the evaluator would return the value as read
            decl.value, decl.static = syntax.init.value, True
        elif not self._evaluate_value(decl):
            return
        if decl.value is not None and not decl.dims and not fits_type(decl.type_name, decl.value):
            try:
                typed_value(decl.type_name, decl.value)
            except ValueShapeError as err:
                decl.value, decl.static = None, False
                decl.reason = f"value does not fit {decl.type_name}: {err}"
        writes = self.writes.get(id(decl))
        if writes:
            first = writes[0]
            line = self.source.line_column(first.offset)[0]
            where = " in a loop" if any(w.in_loop for w in writes) else ""
            decl.static = False
            decl.reason = f"{decl.storage} {decl.name} is {first.how} at line {line}{where}"

    def _evaluate_value(self, decl: Declaration) -> bool:
        """Evaluate the array size and the initial value of `decl` into it; False
        when the size is unknown (and the declaration is then done)."""
        module = decl.module.lower()
        routine = decl.routine.lower() if decl.routine else None
        evaluator = self._evaluator(module, routine)
        try:
            dims = tuple(evaluator.value(d) for d in decl.syntax.dims) if decl.syntax.dims else ()
            decl.dims = tuple(int(d) for d in dims
                              if isinstance(d, float) and d == int(d) and d >= 0)
            if len(decl.dims) != len(dims):
                raise NotConstant("array size is not a whole number")
        except NotConstant as err:
            decl.reason = f"array size unknown: {err.reason}"
            return False
        if decl.syntax.init is None:
            decl.reason = "declared without a value"
        else:
            try:
                decl.value = evaluator.value(decl.syntax.init)
                decl.static = True
            except NotConstant as err:
                decl.reason = err.reason
        return True

    def _name_operand(self, expr: s.NameRef, type_hint: str | None, module: str,
                      routine: str | None) -> tuple:
        """(type name, value, static, reason, declaration) of an Operand that is a data name."""
        found = self._find(expr.name.lower(), module, routine)
        if type(found) is not Declaration or not (self.settled or self.state.get(id(found))):
            value, type_name, static, reason = self._evaluate_operand(
                expr, type_hint, module, routine)
            return type_name, value, static, reason, self._declaration_named(
                expr, module, routine)
        # a resolved declaration: what the evaluator's lookup would give, without it
        if not found.static or found.value is None:
            return type_hint, None, False, f"{found.name}: {found.reason}", found
        kind = found.type_key
        type_name = type_hint or kind
        if type_name != kind:
            try:
                typed_value(type_name, found.value)
            except ValueShapeError as err:
                return type_name, None, False, f"value does not fit {type_name}: {err}", found
        return type_name, found.value, True, None, found

    def _operand(self, arg: s.Argument, type_hint: str | None, module: str,
                 routine: str | None) -> Operand:
        """An operand that is not a plain data name (those are made in _motions)."""
        expr = arg.value
        if expr is None:
            form = "switch" if arg.kind == "optional" else "conditional"
            return Operand(arg, self.source, "", form, static=arg.kind == "optional",
                           reason=None if arg.kind == "optional" else
                           "conditional argument is decided at run time")
        if type(expr) is s.NumericAggregate:  # its value is read already; seldom repeated
            value = expr.value
            if type_hint is not None and fits_type(type_hint, value):
                # an inline target of the instruction's type: what _operand_fields gives
                return Operand(arg, self.source, None, "inline", None, type_hint, value,
                               True, None, None)
            return Operand(arg, self.source, None, *self._operand_fields(
                expr, type_hint, module, routine))
        if type(expr) is s.LazyFunctionCall:
            # `Offs(p7,0,0,10)`: a text that seldom recurs (its first argument changes
            # from move to move), read in one step and not kept: what _operand_fields
            # gives, before the texts of the scope are looked up (the model of the plain
            # grammar's tree, which reads no call lazily, is tested equal)
            known = self._named_call_fields(expr, type_hint, module, routine)
            if known is not None:
                return Operand(arg, self.source, None, *known)
        text = self.source.text[expr.start:expr.end]
        # the same text in the same scope has the same form, value and declaration
        # (every declaration is resolved before the motions are made): read it once
        texts = self.operand_texts.get((module, routine, type_hint))
        if texts is None:
            texts = self.operand_texts[(module, routine, type_hint)] = {}
        known = texts.get(text)
        if known is None:
            known = texts[text] = self._operand_fields(expr, type_hint, module, routine)
        return Operand(arg, self.source, None, *known)

    def _named_call_fields(self, expr: s.LazyFunctionCall, type_hint: str | None, module: str,
                           routine: str | None) -> tuple | None:
        """_operand_fields of a function call of a data name (or an inline value) and
        literals (see Evaluator.named_call), or of such a call and literals
        (`Offs(RelTool(p,0,0,5),0,0,10)`), or None for any other call. A name is looked
        up once, for its value and its declaration."""
        head = expr.head
        if head is None or not self.settled:
            return None
        inner = head.value
        got = self._first_value(inner, module, routine, 1)
        if got is None:
            return None
        first, found = got
        try:
            typed = self._evaluator(module, routine).named_call(expr, first)
        except NotConstant as err:
            fields = (None, type_hint, False, err.reason)
        else:
            if typed is None:
                return None
            fields = self._fitted(*typed, type_hint)
        key = expr.key
        if key == "offs" or key == "reltool":
            name = inner.name if type(inner) is s.NameRef else None
            return (key, name, fields[1], fields[0], fields[2], fields[3], found)
        return ("expression", None, fields[1], fields[0], fields[2], fields[3], None)

    def _name_value(self, name_ref: s.NameRef, module: str, routine: str | None
                    ) -> tuple[object, Declaration | None]:
        """(the value the evaluator's lookup gives a name, or the NotConstant it raises;
        the name's resolved declaration or None)."""
        found = self._find(name_ref.name.lower(), module, routine)
        if type(found) is Declaration:  # resolved: what the evaluator's lookup gives
            if found.static and found.value is not None:
                return found.value, found
            return NotConstant(f"{found.name}: {found.reason}"), found
        try:
            return self._evaluator(module, routine).lookup(name_ref.name)[0], None
        except NotConstant as err:  # without its traceback (see _evaluator)
            return NotConstant(err.reason), None

    #: calls nested deeper than this inside a call's first argument go the general route
    _NESTED_CALLS = 8

    def _first_value(self, expr: s.Expr | None, module: str, routine: str | None,
                     depth: int) -> tuple[object, Declaration | None] | None:
        """(value or NotConstant, declaration or None) of a call's first argument when it
        is a data name, an inline value read already (`Offs([[x,y,z],...],0,0,5)`) or a
        call read in one step (`_nested_value`), else None."""
        if type(expr) is s.NameRef:
            return self._name_value(expr, module, routine)
        if type(expr) is s.NumericAggregate:
            return expr.value, None
        if type(expr) is s.LazyFunctionCall:
            value = self._nested_value(expr, module, routine, depth)
            return None if value is None else (value, None)
        return None

    def _nested_value(self, call: s.LazyFunctionCall, module: str, routine: str | None,
                      depth: int) -> object | None:
        """The value of a call standing as another call's first argument (or the
        NotConstant the evaluator raises for it), when it is a call of a data name or of
        such a call, and literals; None for any other (then the general route decides)."""
        head = call.head
        if head is None or depth > self._NESTED_CALLS:
            return None
        got = self._first_value(head.value, module, routine, depth + 1)
        if got is None:
            return None
        try:
            typed = self._evaluator(module, routine).named_call(call, got[0])
        except NotConstant as err:  # without its traceback (see _evaluator)
            return NotConstant(err.reason)
        return None if typed is None else typed[0]

    def _operand_fields(self, expr: s.Expr, type_hint: str | None, module: str,
                        routine: str | None) -> tuple:
        """(form, name, type name, value, static, reason, declaration) of an operand
        expression that is not a plain data name."""
        base = expr
        if isinstance(expr, (s.Aggregate, s.NumericAggregate)):
            form = "inline"
        elif isinstance(expr, s.Call) and expr.key in ("offs", "reltool"):
            form = expr.key
            head = expr.head if type(expr) is s.LazyFunctionCall else None
            if head is not None:  # its first argument, without making the others
                base = head.value
            else:
                required = [a for a in expr.args if a.kind == "required"]
                base = required[0].value if required else None
        else:
            form = "expression"
        name_ref = base if isinstance(base, s.NameRef) else None
        declaration = None
        if name_ref is not None:
            declaration = self._declaration_named(name_ref, module, routine)
        value, type_name, static, reason = self._evaluate_operand(expr, type_hint, module,
                                                                  routine)
        return (form, name_ref.name if name_ref else None, type_name, value, static, reason,
                declaration)

    def _declaration_named(self, name_ref: s.NameRef, module: str,
                           routine: str | None) -> Declaration | None:
        found = self._find(name_ref.key, module, routine)
        return found if isinstance(found, Declaration) else None

    def _evaluate_operand(self, expr: s.Expr, type_hint: str | None, module: str,
                          routine: str | None) -> tuple[object, str | None, bool, str | None]:
        """(value, type name, static, reason) of an operand expression."""
        try:
            value, kind = self._evaluator(module, routine).typed(expr)
        except NotConstant as err:
            return None, type_hint, False, err.reason
        except RecursionError:
            return None, type_hint, False, "expression nested too deeply to evaluate"
        return self._fitted(value, kind, type_hint)

    @staticmethod
    def _fitted(value: object, kind: str | None, type_hint: str | None
                ) -> tuple[object, str | None, bool, str | None]:
        """(value, type name, static, reason) of an evaluated operand of type `kind`
        where the instruction takes `type_hint`."""
        type_name = type_hint or kind
        if type_name is not None and type_name != kind and not fits_type(type_name, value):
            try:
                typed_value(type_name, value)
            except ValueShapeError as err:
                return None, type_name, False, f"value does not fit {type_name}: {err}"
        return value, type_name, True, None

    def _operands(self, call: s.ProcedureCall, layout: _Layout, module: str,
                  rkey: str) -> tuple[dict[str, Operand], dict[str, Operand]]:
        """(arguments, optional) of a motion instruction's call."""
        source, name_ref, operand, caches = self.source, s.NameRef, Operand, self.name_operands
        roles, n_roles = layout, len(layout)
        arguments: dict[str, Operand] = {}
        optional: dict[str, Operand] = {}
        index = 0
        for arg in call.args:
            if arg.kind == "required":
                if arg.name is None and index < n_roles:
                    key, hint, cache = roles[index]
                else:
                    key = arg.name.lower() if arg.name is not None else f"#{index + 1}"
                    hint = _ROLE_TYPES.get(key)
                    cache = caches.setdefault((module, rkey, hint), {})
                index += 1
                into = arguments
            else:
                key = arg.key or ""
                hint = _ROLE_TYPES.get(key)
                cache = caches.setdefault((module, rkey, hint), {})
                into = optional
            expr = arg.value
            if type(expr) is name_ref:
                # the same speed, zone, tool or target name recurs on many lines
                name = expr.name  # as spelt: no lower()
                cached = cache.get(name)
                if cached is None:
                    cached = cache[name] = self._name_operand(expr, hint, module, rkey)
                # a name's text is its node's string, shared by every use of the name
                into[key] = operand(arg, source, name, "name", name, *cached)
            else:
                into[key] = self._operand(arg, hint, module, rkey)
        return arguments, optional

    def _shared_tail(self, call: s.LazyCall, spec: MotionSpec, layout: _Layout,
                     arguments: dict[str, Operand], optional: dict[str, Operand]
                     ) -> _SharedTail | None:
        """What every call with this call's tail (in the same routine, or in any routine
        that declares nothing) shares, when its leading arguments are its only targets:
        the same text in the same scope gives the same operands (data names, switches,
        `\\V:=120`, any expression)."""
        n_heads = len(call.heads)
        if not n_heads or len(layout) < n_heads or any(
                layout[i][0] not in spec.target_keys for i in range(n_heads)):
            return None
        entries = []
        index = n_heads
        for arg in call.shared_args():
            if arg.name is not None and arg.kind == "required":  # `Name:=value`: by name
                return None
            if arg.kind == "required":
                key = layout[index][0] if index < len(layout) else f"#{index + 1}"
                if key in spec.target_keys:
                    return None
                index += 1
                entries.append((False, key, arguments[key]))
            else:
                entries.append((True, arg.key, None if _own_number(
                    arg.kind, arg.name, arg.value) else optional[arg.key]))
        return _SharedTail(tuple(layout[i][0] for i in range(n_heads)), spec.target_keys,
                           tuple(entries))

    def _layout(self, layouts: dict, spec: MotionSpec, module: str, rkey: str
                ) -> tuple[_Layout, dict[object, _SharedTail | tuple | None]]:
        """`_motions`' per-(instruction, module, routine) tables, made on first use:
        per required position (parameter key, type hint, operand cache), and the
        shared tails of its moves."""
        found = layouts.get((spec, module, rkey))
        if found is None:
            found = layouts[(spec, module, rkey)] = (tuple(
                (key, _ROLE_TYPES.get(key),
                 self.name_operands.setdefault((module, rkey, _ROLE_TYPES.get(key)), {}))
                for key in (p.lower() for p in spec.parameters)), {})
        return found

    def _module_tail(self, call: s.LazyCall, scope: dict[str, object]) -> bool:
        """Whether the shared part of a call (its lead and tail) names nothing its routine
        declares (`scope`): then it means there what it means in every routine of the
        module that declares nothing. Read from the text, every word taken for a name
        (a word in a string too: that only shares less)."""
        heads = call.heads
        if not heads:
            return False
        text = self.source.text
        shared = (text[call.start + len(call.name):heads[0].start]
                  + " " + text[heads[-1].end:call.end])
        return not any(word.lower() in scope for word in _WORDS.findall(shared))

    def _head_operands(self, heads: tuple[s.Argument, ...], layout: _Layout,
                       shared: _SharedTail, module: str, rkey: str) -> list[Operand]:
        """The target operands of a call's leading arguments, in the order of its
        instruction's targets (CirPoint before ToPoint)."""
        targets = []
        for (_, hint, cache), head in zip(layout, heads):
            expr = head.value
            if type(expr) is s.NameRef:
                name = expr.name
                cached = cache.get(name)
                if cached is None:
                    cached = cache[name] = self._name_operand(expr, hint, module, rkey)
                targets.append(Operand(head, self.source, name, "name", name, *cached))
            else:
                targets.append(self._operand(head, hint, module, rkey))
        return [targets[i] for i in shared.head_of_target]

    def _motions(self) -> list[MotionInstruction]:
        """The MotionInstructions of the calls found in pass 2, in program order.

        This runs once per move of a program, so it is written as one loop with
        its tables in local variables. A LazyCall's tail is read once per routine, or
        once for all routines that declare nothing (`_SharedTail`); its moves then only
        need their first argument's operand.
        """
        source, module_names, operands = self.source, self.module_names_as_spelt, self._operands
        name_ref, operand, lazy_call = s.NameRef, Operand, s.LazyCall
        motion, declaration, global_names = MotionInstruction, Declaration, self.global_names
        # (instruction, module, routine) -> per required position: (parameter key,
        # type hint, operand cache: data name as spelt -> what an Operand of it holds),
        # and id(call tail) -> what its moves share (None: nothing; a tuple: the first
        # call's operands, until a second call has the tail; _MODULE_TAIL: the module's
        # table holds it); the calls keep their tails alive while this runs, so an id is
        # not reused
        layouts: dict[tuple[MotionSpec, str, str],
                      tuple[_Layout, dict[object, _SharedTail | tuple | None]]] = {}
        motions: list[MotionInstruction] = []
        last: tuple = (None, None, None)  # consecutive moves mostly share these
        lead_keys: dict[int, object] = {}  # id(call lead) -> _lead_key of it
        pending = self.pending
        for index, (call, spec, module, routine, in_loop) in enumerate(pending):
            pending[index] = None  # its memory is the motion's to use
            if spec.legacy is not None:  # arc welding: Weave required (old) or optional
                spec = spec.for_call(sum(a.kind == "required" for a in call.args))
            if spec is not last[0] or routine is not last[1] or module is not last[2]:
                rkey = routine.lower()
                # the scopes _find looks a name up in, innermost first
                routine_scope = self.routine_names.get((module, rkey), _NONE)
                if not routine_scope:  # a routine that declares nothing (no parameters,
                    # data or FOR variables) sees its module's names: its moves share
                    # operands and tails with those of every such routine
                    rkey = ""
                layout, shared_tails = self._layout(layouts, spec, module, rkey)
                # a routine that declares names shares with the module's routines the
                # tails that hold none of them (`_module_tail`)
                module_tails = self._layout(layouts, spec, module, "")[1] if rkey else None
                last = (spec, routine, module)
                _, head_hint, head_cache = layout[0] if layout else (None, None, None)
                module_scope = self.module_names.get(module, _NONE)
                module_name = module_names[module]
            if type(call) is lazy_call:
                head = call.head
                # (the same tail after one leading argument, after two, or after a lead
                # of switches is shared apart)
                lead = call.lead
                if lead is not None:
                    lead_key = lead_keys.get(id(lead))
                    if lead_key is None:
                        lead_key = lead_keys[id(lead)] = _lead_key(lead)
                    tail = (id(call.tail), lead_key)
                elif call.second is not None:
                    tail = (id(call.tail), 2)
                else:
                    tail = id(call.tail)
                table = shared_tails
                shared = table.get(tail, False)
                if shared is _MODULE_TAIL or (shared is False and module_tails is not None
                                              and self._module_tail(call, routine_scope)):
                    table[tail] = _MODULE_TAIL
                    table = module_tails
                    shared = table.get(tail, False)
                if type(shared) is tuple:  # the second call with this tail: share it now
                    shared = table[tail] = self._shared_tail(*shared)
                if shared is False:  # the first call with this tail: made in full (a
                    # tail that never recurs, `\V:=` on every move, is not shared at all)
                    arguments, optional = operands(call, layout, module, rkey)
                    table[tail] = (call, spec, layout, arguments, optional)
                    shared = None
                elif shared is not None:
                    if call.second is None:  # the usual case: one target
                        expr = head.value
                        if type(expr) is name_ref:
                            name = expr.name
                            cached = head_cache.get(name)
                            if cached is not None:
                                targets = [operand(head, source, name, "name", name, *cached)]
                            else:  # a target name seldom recurs in a CAM program: not kept
                                key = name.lower()
                                found = (routine_scope.get(key) or module_scope.get(key)
                                         or global_names.get(key))
                                if (type(found) is declaration and found.static
                                        and found.value is not None
                                        and (found.type_name == head_hint
                                             or found.type_name.lower() == head_hint)):
                                    # a resolved declaration of the instruction's type:
                                    # what _name_operand gives, without the calls
                                    targets = [operand(head, source, name, "name", name,
                                                       head_hint, found.value, True, None,
                                                       found)]
                                else:
                                    targets = [operand(head, source, name, "name", name,
                                                       *self._name_operand(
                                                           expr, head_hint, module, rkey))]
                        else:
                            targets = [self._operand(head, head_hint, module, rkey)]
                    else:
                        targets = self._head_operands(call.heads, layout, shared, module,
                                                      rkey)
                    motions.append(motion(call.name, spec, module_name, routine,
                                          call, source, targets, in_loop, shared))
                    continue
                else:
                    arguments, optional = operands(call, layout, module, rkey)
            else:
                arguments, optional = operands(call, layout, module, rkey)
            targets = [arguments[key] for key in spec.target_keys if key in arguments]
            motions.append(motion(call.name, spec, module_name, routine, call,
                                  source, targets, in_loop, shared if type(call) is lazy_call
                                  else None, arguments, optional))
        return motions

    # ------------------------------------------------------------ all passes
    def build(self) -> Program:
        """Run the passes and return the finished Program."""
        self._collect()
        for module in self.program.syntax.modules:
            for item in module.items:
                if isinstance(item, s.Routine):
                    self._scan_routine(item, module.name.lower())
        for module in reversed(self.program.modules):  # the first of a name wins
            self.module_names_as_spelt[module.name.lower()] = module.name
        state, resolve, writes = self.state, self._resolve, self.writes
        numeric_aggregate = s.NumericAggregate
        for decl in self.program.declarations:
            key = id(decl)
            if key in state:
                continue
            # the bulk of a CAM program, as _resolve would do it: an all-numeric
            # value of the declared shape, never written to
            syntax = decl.syntax
            init = syntax.init
            if (type(init) is numeric_aggregate and not syntax.dims and key not in writes
                    and fits_type(decl.type_name, init.value)):
                decl.value, decl.static = init.value, True
                state[key] = True
            else:
                resolve(decl)
        self.settled = True
        for evaluator in self.evaluators.values():
            evaluator.tails = {}
        self.state = {}  # not needed any more: its memory is the motions' to use
        self.program.motions = self._motions()
        # The evaluators' lookups refer back to this builder: break that cycle so
        # that reference counting frees the builder's tables at once.
        self.evaluators.clear()
        return self.program


def build_program(source: SourceText, kept_bytes: bytes | None,
                  tree: s.SourceFile) -> Program:
    """The Program model of a parsed file; `kept_bytes` as `Program.kept_bytes`."""
    return ModelBuilder(source, kept_bytes, tree).build()
