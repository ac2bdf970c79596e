"""Which component field a system wrote through a read-only view.

A system's views of the components it only reads are NumPy arrays marked read-only, so a write
to one fails inside NumPy with a bare "assignment destination is read-only". Checking writes as
they happen would cost every system that behaves; instead the world catches that error when a
system ends with it and asks this module what was written. It reads the failing statement's
source (the traceback's exact position), finds the array expressions in it and evaluates only
names, a batch's `[Component]` or `[Component.field]` and a view's fields (nothing that runs user
code), then matches the arrays against the tables' columns.
"""

from __future__ import annotations

import ast
import builtins
import linecache
from collections.abc import Iterable, Iterator
from types import FrameType, ModuleType, TracebackType
from typing import Any, Protocol

import numpy as np

from .errors import AccessError
from .query import Batch, ComponentView
from .schema import Component
from .table import ArchetypeTable

_NUMPY_SAYS = ("assignment destination is read-only", "output array is read-only")


class _Unknown(Exception):
    """An expression this module does not evaluate (it could run user code)."""


class WritingSystem(Protocol):
    name: str
    writes: frozenset[type] | None


def is_read_only_write(exc: BaseException) -> bool:
    return isinstance(exc, ValueError) and any(s in str(exc) for s in _NUMPY_SAYS)


def read_only_write_error(exc: ValueError, system: WritingSystem, tables: Iterable[ArchetypeTable]) -> AccessError:
    """The AccessError for a system whose run ended in NumPy's read-only error `exc`: it names
    the system, the component and field (or the entity ids) and where, when the source says."""
    ids = {id(table.entities) for table in tables}
    columns = {id(column): key for table in tables for key, column in table.columns.items()}
    for frame, lineno, segment in _statements(exc.__traceback__):
        owners = [id(_owner(a)) for a in _written_arrays(segment, frame)]
        found = sorted({columns[o] for o in owners if o in columns}, key=lambda k: (k[0].__name__, k[1]))
        where = f"{frame.f_code.co_filename}:{lineno}"
        if found:
            what = " or ".join(f"{ct.__name__}.{name}" for ct, name in found)
            components = {ct for ct, _ in found}
            if system.writes is not None and not components <= system.writes:
                missing = ", ".join(sorted(ct.__name__ for ct in components - system.writes))
                return AccessError(
                    f"system {system.name} writes {what} ({where}) but declares {missing} read-only: "
                    f"add {missing} to its writes to change it"
                )
            return AccessError(
                f"system {system.name} writes {what} ({where}) through a query that asked for it "
                "read-only: list it in the query's write=[...]"
            )
        if any(o in ids for o in owners):
            return AccessError(
                f"system {system.name} writes batch.entities ({where}): entity ids are read-only; "
                "spawn or destroy entities instead"
            )
    return AccessError(f"system {system.name} wrote to a read-only view (a component it only reads): {exc}")


def _statements(tb: TracebackType | None) -> Iterator[tuple[FrameType, int, str]]:
    """(frame, line, source of the failing expression) per traceback entry, innermost first."""
    entries = []
    while tb is not None:
        entries.append(tb)
        tb = tb.tb_next
    for entry in reversed(entries):
        code = entry.tb_frame.f_code
        positions = list(code.co_positions())
        index = entry.tb_lasti // 2
        if index >= len(positions):
            continue
        start, end, col, end_col = positions[index]
        if start is None or end is None or col is None or end_col is None:
            continue
        lines = [linecache.getline(code.co_filename, n) for n in range(start, end + 1)]
        if not all(lines):
            continue
        lines[-1] = lines[-1][:end_col]
        lines[0] = lines[0][col:]
        yield entry.tb_frame, entry.tb_lineno, "".join(lines)


def _written_arrays(segment: str, frame: FrameType) -> list[np.ndarray]:
    """The arrays a failing expression writes: a store's or an augmented assignment's target
    (less its last subscript), a call's `out=` (else every argument)."""
    try:
        tree: ast.AST = ast.parse(f"({segment})", mode="eval").body
    except SyntaxError:
        try:
            tree = ast.parse(segment.strip(), mode="exec").body[0]
        except (SyntaxError, IndexError):
            return []
    candidates: list[ast.expr]
    if isinstance(tree, ast.AugAssign):
        candidates = [tree.target]
    elif isinstance(tree, ast.Call):
        outs = [k.value for k in tree.keywords if k.arg == "out"]
        candidates = outs or [*tree.args, *(k.value for k in tree.keywords)]
    elif isinstance(tree, ast.expr):  # a store's target
        candidates = [tree]
    else:
        return []
    arrays = []
    for node in candidates:
        while True:  # `batch[C].field[rows]`: the array is what the last subscript indexes
            try:
                value = _value(node, frame)
            except Exception:  # _Unknown, or a lookup that failed: nothing learned here
                value = None
            if isinstance(value, np.ndarray):
                arrays.append(value)
                break
            if not isinstance(node, ast.Subscript):
                break
            node = node.value
    return arrays


def _value(node: ast.AST, frame: FrameType) -> Any:
    """Evaluate names, a batch's `[...]`, a view's or a module's attributes; nothing else."""
    if isinstance(node, ast.Name):
        for scope in (frame.f_locals, frame.f_globals, vars(builtins)):
            if node.id in scope:
                return scope[node.id]
        raise _Unknown(node.id)
    if isinstance(node, ast.Attribute):
        base = _value(node.value, frame)
        if isinstance(base, ComponentView | ModuleType):
            return vars(base)[node.attr]
        if isinstance(base, type) and issubclass(base, Component):
            return base.__fields__[node.attr]
        if isinstance(base, Batch) and node.attr == "entities":
            return base.entities
        raise _Unknown(node.attr)
    if isinstance(node, ast.Subscript):
        base = _value(node.value, frame)
        if isinstance(base, Batch):
            return base[_value(node.slice, frame)]
        raise _Unknown("subscript")
    raise _Unknown(type(node).__name__)


def _owner(array: np.ndarray) -> np.ndarray:
    """The array that owns the memory of a view (a column, or a table's ids)."""
    while isinstance(array.base, np.ndarray):
        array = array.base
    return array
