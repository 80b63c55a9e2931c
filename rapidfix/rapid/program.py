"""The program model: what the post-processor needs from a RAPID file.

Declarations with their evaluated values, routines, and every motion
instruction with its targets, speed, zone, tool, work object and optional
arguments — each with the span it came from, so that rapidfix.rapid.edit can
rewrite exactly that text. Built by rapidfix.rapid.model_builder.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Protocol

from rapidfix.rapid import syntax as s
from rapidfix.rapid.instructions import MotionSpec
from rapidfix.rapid.scope import find_visible
from rapidfix.rapid.source import SourceText
from rapidfix.rapid.span import Span
from rapidfix.rapid.values import TARGET_TYPES, Value, ValueShapeError, typed_value


@dataclass(eq=False, slots=True)
class Declaration:
    """A data declaration (`CONST robtarget p10 := [...];`), module or routine level.

    `value` is the evaluated initial value (None when there is none or it
    cannot be evaluated); `static` says whether that value holds for the whole
    run, and `reason` why not.
    """

    name: str
    type_name: str
    storage: str  # 'CONST' | 'VAR' | 'PERS'
    module: str
    routine: str | None
    syntax: s.DataDecl = field(repr=False)
    source: SourceText = field(repr=False)
    local: bool = False
    task: bool = False
    dims: tuple[int, ...] = ()
    value: Value | None = None
    static: bool = False
    reason: str | None = None

    @property
    def key(self) -> str:
        return self.name.lower()

    @property
    def type_key(self) -> str:
        return self.type_name.lower()

    # Spans are made when asked, from the syntax node: a CAM program has
    # hundreds of thousands of declarations.
    @property
    def span(self) -> Span:
        """The whole declaration, up to and including ';'."""
        return Span(self.syntax.start, self.syntax.end, self.source)

    @property
    def name_span(self) -> Span:
        start = self.syntax.name_start
        return Span(start, start + len(self.syntax.name), self.source)

    @property
    def value_span(self) -> Span | None:
        """The initial value expression (None without one)."""
        init = self.syntax.init
        return None if init is None else Span(init.start, init.end, self.source)

    @property
    def is_target(self) -> bool:
        """A robtarget or jointtarget (scalar or array)."""
        return self.type_key in TARGET_TYPES

    @property
    def data(self) -> Any:
        """Typed view of the value (RobTarget, ToolData, ...) or None."""
        if self.value is None or self.dims:
            return None
        try:
            return typed_value(self.type_name, self.value)
        except ValueShapeError:
            return None


@dataclass(eq=False, slots=True)
class Operand:
    """One argument of an instruction, with its value when it is known.

    `form`: 'name' (a plain data name), 'inline' (an aggregate), 'offs',
    'reltool', 'expression', or 'switch' (an optional argument with no value).
    """

    argument: s.Argument = field(repr=False)
    source: SourceText = field(repr=False)
    # the expression's text when it was at hand (a data name), None: `text` reads it from
    # the source when asked (a CAM program's inline targets would each keep a copy)
    given_text: str | None
    form: str
    name: str | None = None  # the data name for form 'name' (and Offs/RelTool base)
    type_name: str | None = None
    value: Value | None = None
    static: bool = False
    reason: str | None = None
    declaration: Declaration | None = field(default=None, repr=False)

    @property
    def text(self) -> str:
        """The source text of the expression ('' for a switch or a conditional argument)."""
        text = self.given_text
        if text is None:
            value = self.argument.value
            return "" if value is None else self.source.text[value.start:value.end]
        return text

    # Spans are made when asked: a CAM program has millions of operands.
    @property
    def span(self) -> Span:
        """The whole argument, including `\\Name:=` for optional ones."""
        return Span(self.argument.start, self.argument.end, self.source)

    @property
    def value_span(self) -> Span | None:
        """The expression only (None for a switch or a conditional argument)."""
        value = self.argument.value
        return None if value is None else Span(value.start, value.end, self.source)

    @property
    def data(self) -> Any:
        """Typed view of the value when its type is known, else None."""
        if self.value is None or self.type_name is None:
            return None
        try:
            return typed_value(self.type_name, self.value)
        except ValueShapeError:
            return None


class SharedOperands(Protocol):
    """Makes the operands of motions that share everything but their targets."""

    def operands(self, motion: MotionInstruction) -> tuple[dict[str, Operand],
                                                          dict[str, Operand]]:
        """(arguments, optional) of `motion`, its `targets` among them."""


@dataclass(eq=False, slots=True)
class MotionInstruction:
    """A call of a motion instruction (MoveL, MoveAbsJ, TriggC, ...).

    `arguments` (required parameters by lower-case spec name) and `optional`
    (optional arguments by lower-case name) hold an Operand per argument;
    `targets` the target operands among them, CirPoint before ToPoint.

    `shared` is not None when the instruction's operands other than its targets
    are those of every motion with the same `shared` object: the same text,
    values, declarations and reasons (a CAM program's moves differ only in their
    targets). Such motions make `arguments` and `optional` when first asked for.
    """

    name: str
    spec: MotionSpec = field(repr=False)
    module: str
    routine: str
    syntax: s.ProcedureCall = field(repr=False)
    source: SourceText = field(repr=False)
    targets: list[Operand]
    in_loop: bool = False
    shared: SharedOperands | None = field(default=None, repr=False)
    _arguments: dict[str, Operand] | None = field(default=None, repr=False)
    _optional: dict[str, Operand] | None = field(default=None, repr=False)

    @property
    def arguments(self) -> dict[str, Operand]:
        """Required parameters by lower-case spec name."""
        if self._arguments is None:
            self._arguments, self._optional = self.shared.operands(self)
        return self._arguments

    @property
    def optional(self) -> dict[str, Operand]:
        """Optional arguments by lower-case name."""
        if self._optional is None:
            self._arguments, self._optional = self.shared.operands(self)
        return self._optional

    @property
    def span(self) -> Span:
        """The whole statement, including ';'."""
        return Span(self.syntax.start, self.syntax.end, self.source)

    @property
    def name_span(self) -> Span:
        start = self.syntax.start
        return Span(start, start + len(self.syntax.name), self.source)

    @property
    def target(self) -> Operand | None:
        """The destination (ToPoint / ToJointPos)."""
        targets = self.targets
        return targets[-1] if targets else None

    @property
    def target_kind(self) -> str:
        return self.spec.target_kind

    @property
    def speed(self) -> Operand | None:
        return self.arguments.get("speed")

    @property
    def zone(self) -> Operand | None:
        return self.arguments.get("zone")

    @property
    def tool(self) -> Operand | None:
        return self.arguments.get("tool")

    @property
    def wobj(self) -> Operand | None:
        return self.optional.get("wobj")


@dataclass(eq=False)
class RoutineInfo:
    name: str
    kind: str  # 'PROC' | 'FUNC' | 'TRAP'
    module: str
    span: Span
    syntax: s.Routine = field(repr=False)

    @property
    def parameters(self) -> list[s.Parameter]:
        return self.syntax.parameters


@dataclass(eq=False)
class ModuleInfo:
    """A module; `declarations_end` is where new module data can be inserted
    (just after the last module-level declaration, or after the MODULE line)."""

    name: str
    attributes: list[str]
    span: Span
    header_end: int
    declarations_end: int
    syntax: s.Module = field(repr=False)


@dataclass(eq=False)
class Program:
    """A parsed RAPID file: its source, syntax tree and model."""

    source: SourceText = field(repr=False)
    #: the file's bytes when its text does not encode back to exactly them, else None:
    #: then `original` encodes the text again, and a large file is not held twice
    kept_bytes: bytes | None = field(repr=False)
    syntax: s.SourceFile = field(repr=False)
    modules: list[ModuleInfo] = field(default_factory=list)
    declarations: list[Declaration] = field(default_factory=list)
    routines: list[RoutineInfo] = field(default_factory=list)
    motions: list[MotionInstruction] = field(default_factory=list)
    #: the procedure calls that are not motion instructions, each with its routine, in
    #: the order of the routines and their bodies (the model builder's walk)
    other_calls: list[tuple[s.ProcedureCall, s.Routine]] = field(default_factory=list,
                                                                 repr=False)
    _by_name: dict[str | None, dict[str, Declaration]] | None = field(default=None, repr=False)
    _indexed: int = field(default=0, repr=False)

    @property
    def filename(self) -> str:
        return self.source.filename

    @property
    def text(self) -> str:
        return self.source.text

    @property
    def original(self) -> bytes:
        """The file exactly as it was read."""
        return self.source.encode() if self.kept_bytes is None else self.kept_bytes

    @property
    def encoding(self) -> str:
        return self.source.encoding

    @property
    def bom(self) -> bytes:
        return self.source.bom

    @property
    def newline(self) -> str:
        """The file's dominant line ending ('\\n', '\\r\\n' or a lone '\\r')."""
        return self.source.newline

    @property
    def header(self) -> str | None:
        """The `%%% ... %%%` block of a .prg file, or None."""
        return self.syntax.header

    def span(self, start: int, end: int) -> Span:
        """A span of this program's text."""
        return Span(start, end, self.source)

    def declaration(self, name: str, routine: str | None = None) -> Declaration | None:
        """The declaration `name` visible in `routine` (or at module level), any case."""
        if self._by_name is None or self._indexed != len(self.declarations):
            scopes: dict[str | None, dict[str, Declaration]] = {}
            for decl in self.declarations:  # the first declaration of a name in a scope
                routine_key = None if decl.routine is None else decl.routine.lower()
                scopes.setdefault(routine_key, {}).setdefault(decl.key, decl)
            self._by_name, self._indexed = scopes, len(self.declarations)
        scopes = self._by_name
        routine_scope = {} if routine is None else scopes.get(routine.lower(), {})
        return find_visible(name.lower(), routine_scope, scopes.get(None, {}))

    def to_bytes(self) -> bytes:
        """The file exactly as it was read."""
        return self.original
