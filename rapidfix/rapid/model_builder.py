"""Build the program model from a syntax tree in a few linear passes.

1. collect modules, records, routines and declarations with their scopes;
2. walk every routine's statements once: note where data is written
   (assignments, INOUT/VAR arguments, SearchL's SearchPoint, ...) and collect
   the motion instructions with their loop depth;
3. evaluate declarations (memoised, in dependency order) and the operands of
   every motion instruction, recording why a value is not static.
"""

from __future__ import annotations

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
from rapidfix.rapid.source import SourceText
from rapidfix.rapid.system_data import SYSTEM_DATA
from rapidfix.rapid.values import ValueShapeError, typed_value

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


def _root_name(expr: s.Expr | None) -> s.NameRef | None:
    while isinstance(expr, (s.Index, s.Component)):
        expr = expr.base
    return expr if isinstance(expr, s.NameRef) else None


class ModelBuilder:
    """Builds a Program from source text and its syntax tree (see the module doc)."""

    def __init__(self, source: SourceText, original: bytes, tree: s.SourceFile) -> None:
        self.source = source
        self.program = Program(source, original, tree)
        self.module_names: dict[str, dict[str, Declaration]] = {}
        self.global_names: dict[str, Declaration] = {}
        self.routine_names: dict[tuple[str, str], dict[str, object]] = {}
        self.user_routines: dict[str, s.Routine] = {}
        self.records: dict[str, tuple[tuple[str, str], ...]] = {}
        self.writes: dict[int, list[_Write]] = {}
        self.state: dict[int, bool] = {}  # False while evaluating, True when done
        self.evaluators: dict[tuple[str, str | None], Evaluator] = {}
        self.name_operands: dict[tuple, tuple] = {}
        self.pending: list[tuple[s.ProcedureCall, MotionSpec, str, str, bool]] = []
        self.spec_keys: dict[str, tuple[str, ...]] = {}  # instruction -> lower-case parameters

    # ------------------------------------------------------------ pass 1
    def _declaration(self, decl: s.DataDecl, module: str, routine: str | None) -> Declaration:
        return Declaration(
            name=decl.name, type_name=decl.type_name, storage=decl.storage, module=module,
            routine=routine, syntax=decl, source=self.source, local=decl.local, task=decl.task,
        )

    def _collect(self) -> None:
        program = self.program
        for module in program.syntax.modules:
            mkey = module.name.lower()
            names = self.module_names.setdefault(mkey, {})
            last_decl_end = module.header_end
            for item in module.items:
                if isinstance(item, s.DataDecl):
                    decl = self._declaration(item, module.name, None)
                    program.declarations.append(decl)
                    names.setdefault(decl.key, decl)
                    if not decl.local:
                        self.global_names.setdefault(decl.key, decl)
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
        if routine is not None:
            found = self.routine_names.get((module, routine), {}).get(key)
            if found is not None:
                return found
        found = self.module_names.get(module, {}).get(key)
        return found if found is not None else self.global_names.get(key)

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
            def lookup(name: str) -> TypedValue:
                return self._lookup(name, module, routine)
            evaluator = self.evaluators[key] = Evaluator(lookup, self.records)
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
                in_loop = loops > 0
                if isinstance(statement, s.Assignment):
                    self._note_write(statement.target, module, rkey,
                                     "assigned", statement.start, in_loop)
                elif isinstance(statement, s.ProcedureCall):
                    self._scan_call(statement, module, routine, in_loop)
                elif isinstance(statement, s.For):
                    scope.setdefault(statement.variable.lower(),
                                     _LoopVariable(statement.variable))

    def _scan_call(self, call: s.ProcedureCall, module: str, routine: s.Routine,
                   in_loop: bool) -> None:
        spec = motion_spec(call.name)
        if spec is not None:
            self.pending.append((call, spec, module, routine.name, in_loop))
        positions, names = self._written_positions(call)
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
            return
        if decl.syntax.init is None:
            decl.reason = "declared without a value"
        else:
            try:
                decl.value = evaluator.value(decl.syntax.init)
                decl.static = True
            except NotConstant as err:
                decl.reason = err.reason
        if decl.value is not None and not decl.dims:
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

    def _operand(self, arg: s.Argument, type_hint: str | None, module: str,
                 routine: str | None) -> Operand:
        expr = arg.value
        if expr is None:
            form = "switch" if arg.kind == "optional" else "conditional"
            return Operand(arg, self.source, "", form, static=arg.kind == "optional",
                           reason=None if arg.kind == "optional" else
                           "conditional argument is decided at run time")
        if isinstance(expr, s.NameRef):
            # the same speed, zone, tool or target name recurs on many lines
            cache_key = (module, routine, expr.name, type_hint)  # as spelt: no lower()
            cached = self.name_operands.get(cache_key)
            if cached is None:
                value, type_name, static, reason = self._evaluate_operand(
                    expr, type_hint, module, routine)
                cached = self.name_operands[cache_key] = (
                    type_name, value, static, reason,
                    self._declaration_named(expr, module, routine))
            # a name's text is its node's string, shared by every use of the name
            return Operand(arg, self.source, expr.name, "name", expr.name, *cached)
        text = self.source.text[expr.start:expr.end]
        base = expr
        if isinstance(expr, (s.Aggregate, s.NumericAggregate)):
            form = "inline"
        elif isinstance(expr, s.Call) and expr.key in ("offs", "reltool"):
            form = expr.key
            required = [a for a in expr.args if a.kind == "required"]
            base = required[0].value if required else None
        else:
            form = "expression"
        name_ref = base if isinstance(base, s.NameRef) else None
        operand = Operand(arg, self.source, text, form,
                          name=name_ref.name if name_ref else None, type_name=type_hint)
        if name_ref is not None:
            operand.declaration = self._declaration_named(name_ref, module, routine)
        cached = self._evaluate_operand(expr, type_hint, module, routine)
        operand.value, operand.type_name, operand.static, operand.reason = cached
        return operand

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
        type_name = type_hint or kind
        if type_name is not None and type_name != kind:
            try:
                typed_value(type_name, value)
            except ValueShapeError as err:
                return None, type_name, False, f"value does not fit {type_name}: {err}"
        return value, type_name, True, None

    def _motion(self, call: s.ProcedureCall, spec: MotionSpec, module: str, routine: str,
                in_loop: bool) -> MotionInstruction:
        rkey = routine.lower()
        keys = self.spec_keys.get(spec.name)
        if keys is None:
            keys = self.spec_keys[spec.name] = tuple(p.lower() for p in spec.parameters)
        arguments: dict[str, Operand] = {}
        optional: dict[str, Operand] = {}
        index = 0
        for arg in call.args:
            if arg.kind == "required":
                if arg.name is not None:
                    key = arg.name.lower()
                elif index < len(keys):
                    key = keys[index]
                else:
                    key = f"#{index + 1}"
                index += 1
                arguments[key] = self._operand(arg, _ROLE_TYPES.get(key), module, rkey)
            else:
                key = arg.key or ""
                optional[key] = self._operand(arg, _ROLE_TYPES.get(key), module, rkey)
        return MotionInstruction(
            name=call.name, spec=spec, module=self._module_name(module), routine=routine,
            syntax=call, source=self.source, arguments=arguments, optional=optional,
            in_loop=in_loop,
        )

    def _module_name(self, key: str) -> str:
        for module in self.program.modules:
            if module.name.lower() == key:
                return module.name
        return key  # pragma: no cover - every key comes from a module

    # ------------------------------------------------------------ all passes
    def build(self) -> Program:
        """Run the passes and return the finished Program."""
        self._collect()
        for module in self.program.syntax.modules:
            for item in module.items:
                if isinstance(item, s.Routine):
                    self._scan_routine(item, module.name.lower())
        for decl in self.program.declarations:
            self._resolve(decl)
        self.program.motions = [self._motion(*pending) for pending in self.pending]
        return self.program


def build_program(source: SourceText, original: bytes, tree: s.SourceFile) -> Program:
    """The Program model of a parsed file."""
    return ModelBuilder(source, original, tree).build()
