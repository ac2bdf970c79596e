"""Component schemas: a component type is a class whose fields each become one NumPy column.

    class Health(Component):
        hp = Field("f4", default=100.0, finite=True, minimum=0.0)
        regen = Field("f4", (2,), default=(0.0, 1.0))

`Health(hp=50)` is a value bundle used to spawn, add or set; its fields may hold one value (shared
by every entity in a batch) or an array with one row per entity. Values are checked when they
reach the world (the API boundary), where the failing entity can be named; systems writing through
column views are trusted and pay nothing.
"""

from __future__ import annotations

import itertools
from collections.abc import Callable
from typing import Any, ClassVar, cast

import numpy as np

_component_ids = itertools.count(1)

# Rows whose quaternion/vector length is below this cannot be normalised and are rejected.
UNIT_EPSILON = 1e-12


def describe_row(row: int) -> str:
    return f"row {row} of the batch"


class Field:
    """One column of a component: dtype, per-entity shape, default and the checks on write."""

    def __init__(
        self,
        dtype: Any,
        shape: tuple[int, ...] | int = (),
        default: Any = ...,
        *,
        finite: bool = False,
        allow_posinf: bool = False,
        minimum: float | None = None,
        min_exclusive: bool = False,
        maximum: float | None = None,
        unit: bool = False,
        entity: bool = False,
        doc: str = "",
    ) -> None:
        self.dtype = np.dtype(dtype)
        # `entity`: the field holds entity ids (int64; -1 or any dead id: none), so saved scenes
        # remap it on load and the hierarchy follows it
        if entity and (self.dtype != np.int64):
            raise TypeError(f"an entity field holds int64 ids, not {self.dtype}")
        self.entity = entity
        self.shape = (shape,) if isinstance(shape, int) else tuple(shape)
        self.finite = finite
        self.allow_posinf = allow_posinf
        self.minimum = minimum
        self.min_exclusive = min_exclusive
        self.maximum = maximum
        self.unit = unit
        self.doc = doc
        self.name = "?"
        self.component: type[Component] | None = None
        if default is ...:
            default = None if self.dtype == object else 0  # no value: None for objects, zero for numbers
        if self.dtype == object:
            self.default = default
            self._default_row = np.empty(1, dtype=object)  # one value for every row, even a list
            self._default_row[0] = default
        else:
            self.default = np.broadcast_to(np.asarray(default, dtype=self.dtype), self.shape).copy()
            self.default.flags.writeable = False
            self._default_row = self.default[None]

    def __set_name__(self, owner: type, name: str) -> None:
        self.name = name
        self.component = cast("type[Component]", owner)  # set on Component subclasses only

    @property
    def qualname(self) -> str:
        owner = self.component.__name__ if self.component is not None else "?"
        return f"{owner}.{self.name}"

    @property
    def fill_value(self) -> Any:
        """What `column[rows] = ...` takes to give every row the default (an object field's
        default may itself be a sequence, so it goes in a one-element object array)."""
        return self._default_row if self.is_object else self.default

    @property
    def is_object(self) -> bool:
        return self.dtype == object

    def __repr__(self) -> str:
        return f"Field({self.qualname}, {self.dtype}, shape={self.shape})"

    # ------------------------------------------------------------------ checks
    def coerce(self, value: Any, n: int, who: Callable[[int], str] = describe_row) -> np.ndarray:
        """Return `value` as an array of shape (1, *shape) (shared) or (n, *shape), checked and
        normalised.

        Raises ValueError naming `who(row)` and the field on any bad row; never mutates storage.
        """
        if self.is_object:
            return self._coerce_object(value, n)
        if value is self.default:
            return self._default_row  # the default passed its checks when the schema was made
        arr = value if isinstance(value, np.ndarray) else np.asarray(value)
        if arr.dtype != self.dtype:
            arr = self._cast(arr, value, who)
        if arr.shape != self.shape and arr.shape != (n, *self.shape) and arr.shape != (1, *self.shape):
            per = self.shape if self.shape else "a scalar"
            raise ValueError(
                f"{self.qualname} expects {per} per entity, or shape {(n, *self.shape)} for "
                f"{n} entities; got shape {arr.shape}"
            )
        if self.finite or self.minimum is not None or self.maximum is not None:
            self._check_range(arr, who)
        if self.unit:
            arr = self._normalise(arr, who)
        return arr[None] if arr.shape == self.shape else arr

    def _cast(self, arr: np.ndarray, value: Any, who: Callable[[int], str]) -> np.ndarray:
        """Same-kind casts, plus any integer into an integer field when every value fits."""
        target = self.dtype
        if arr.dtype.kind in "iub" and target.kind in "iu":
            if arr.size:
                info = np.iinfo(target)
                rows = self._rows((arr < info.min) | (arr > info.max))
                if rows.any():
                    self._fail(rows, arr, who, f"must fit in {target} ({info.min}..{info.max})")
            return arr.astype(target)
        if arr.dtype == object or not np.can_cast(arr.dtype, target, casting="same_kind"):
            raise ValueError(f"{self.qualname} holds {target} values; got {arr.dtype} ({_preview(value)})")
        if target.kind == "f" and arr.dtype.kind == "f" and arr.dtype.itemsize > target.itemsize and arr.size:
            largest = float(np.finfo(target).max)  # beyond it the cast would make a finite value inf
            rows = self._rows(np.isfinite(arr) & (np.abs(arr) > largest))
            if rows.any():
                self._fail(rows, arr, who, f"must fit in {target} (magnitude at most {largest:.3g})")
        if target.kind == "U" and arr.dtype.kind == "U" and arr.dtype.itemsize > target.itemsize and arr.size:
            longest = target.itemsize // 4  # a cast would cut longer strings short without a word
            rows = self._rows(np.char.str_len(arr) > longest)
            if rows.any():
                self._fail(rows, arr, who, f"is at most {longest} characters long")
        return arr.astype(target)

    def _coerce_object(self, value: Any, n: int) -> np.ndarray:
        """The rule for object fields, the same for every n: a NumPy object array of shape (n,)
        gives one value per row; any other value (a string, a list, None, ...) is one value
        shared by every row. Returns shape (n,) or (1,) (shared)."""
        if isinstance(value, np.ndarray) and value.dtype == object and value.shape == (n,):
            return value
        out = np.empty(1, dtype=object)
        out[0] = value
        return out

    def _rows(self, mask: np.ndarray) -> np.ndarray:
        """Collapse a per-element mask to a per-row mask (shape () means one row)."""
        extra = len(self.shape)
        if mask.ndim > extra:
            # the width spelled out: reshape(0, -1) is ambiguous, and a batch of 0 rows is allowed
            return np.asarray(mask.reshape(mask.shape[0], int(np.prod(mask.shape[1:]))).any(axis=1))
        return np.atleast_1d(mask.any()) if extra else np.atleast_1d(mask)

    def _fail(self, rows: np.ndarray, arr: np.ndarray, who: Callable[[int], str], what: str) -> None:
        row = int(np.flatnonzero(rows)[0])
        shown = arr[row] if arr.ndim > len(self.shape) else arr
        count = int(rows.sum())
        more = f" ({count} rows fail)" if count > 1 else ""
        raise ValueError(f"{who(row)}: {self.qualname} {what}, got {_preview(shown)}{more}")

    def _check_range(self, arr: np.ndarray, who: Callable[[int], str]) -> None:
        if self.finite and arr.dtype.kind in "fc":
            bad = np.isnan(arr)
            if self.allow_posinf:
                bad |= np.isneginf(arr)
                what = "must not be NaN or -inf"
            else:
                bad |= np.isinf(arr)
                what = "must be finite (no NaN or Inf)"
            rows = self._rows(bad)
            if rows.any():
                self._fail(rows, arr, who, what)
        if self.minimum is not None:
            bad = arr <= self.minimum if self.min_exclusive else arr < self.minimum
            rows = self._rows(bad)
            if rows.any():
                op = ">" if self.min_exclusive else ">="
                self._fail(rows, arr, who, f"must be {op} {self.minimum:g}")
        if self.maximum is not None:
            rows = self._rows(arr > self.maximum)
            if rows.any():
                self._fail(rows, arr, who, f"must be <= {self.maximum:g}")

    def _normalise(self, arr: np.ndarray, who: Callable[[int], str]) -> np.ndarray:
        """Unit length per row. Scaled by the largest component first, so huge finite values
        (1e200) do not overflow the squares and tiny ones do not underflow them."""
        peak = np.max(np.abs(arr), axis=-1, keepdims=True)
        safe = np.where(peak > 0.0, peak, 1.0)
        scaled = arr / safe
        norm = np.linalg.norm(scaled, axis=-1, keepdims=True)
        rows = np.atleast_1d(peak[..., 0] < UNIT_EPSILON)  # the length lies between peak and 2 * peak
        if rows.any():
            self._fail(rows, arr, who, "must have non-zero length (it is normalised on write)")
        return scaled / norm


class Component:
    """Base class of component schemas. Subclasses declare `Field`s as class attributes."""

    __fields__: ClassVar[dict[str, Field]] = {}
    # Components added automatically (with defaults) to any entity that gets this one.
    required: ClassVar[tuple[type[Component], ...]] = ()
    component_id: ClassVar[int] = 0

    def __init_subclass__(cls, **kwargs: Any) -> None:
        super().__init_subclass__(**kwargs)
        fields: dict[str, Field] = {}
        for base in reversed(cls.__mro__[1:]):
            fields.update(getattr(base, "__fields__", {}))
        for name, value in cls.__dict__.items():
            if isinstance(value, Field):
                if name.startswith("_") or name in ("required", "component_id"):
                    raise TypeError(f"{cls.__name__}: field name {name!r} is reserved")
                fields[name] = value
        cls.__fields__ = fields
        cls.component_id = next(_component_ids)

    def __init__(self, **values: Any) -> None:
        unknown = set(values) - set(self.__fields__)
        if unknown:
            raise TypeError(
                f"{type(self).__name__} has no field(s) {sorted(unknown)}; its fields are {list(self.__fields__)}"
            )
        for name, f in self.__fields__.items():
            setattr(self, name, values[name] if name in values else f.default)

    @classmethod
    def check(cls, values: dict[str, np.ndarray], who: Callable[[int], str]) -> None:
        """Cross-field checks on coerced values (arrays of 1 or n rows); raise ValueError."""

    def values(self) -> dict[str, Any]:
        return {name: getattr(self, name) for name in self.__fields__}

    def __repr__(self) -> str:
        inner = ", ".join(f"{k}={_preview(v)}" for k, v in self.values().items())
        return f"{type(self).__name__}({inner})"

    def __eq__(self, other: object) -> bool:
        if type(other) is not type(self):
            return NotImplemented
        return all(_equal(getattr(self, k), getattr(other, k)) for k in self.__fields__)

    __hash__ = None  # type: ignore[assignment]


def _equal(a: Any, b: Any) -> bool:
    if isinstance(a, np.ndarray) or isinstance(b, np.ndarray):
        return bool(np.array_equal(np.asarray(a), np.asarray(b)))
    return bool(a == b)


def _preview(value: Any) -> str:
    if isinstance(value, np.ndarray):
        if value.size > 8:
            return f"array of shape {value.shape}"
        return repr(value.tolist())
    if isinstance(value, np.generic):
        value = value.item()  # 1e+300, not np.float64(1e+300)
    text = repr(value)
    return text if len(text) <= 60 else text[:57] + "..."


class ObjectStore(Component):
    """Storage schema for an arbitrary Python class used as a component (esper style)."""

    value = Field(object, default=None)


def object_component(py_type: type) -> type[Component]:
    """A one-column object schema standing for `py_type` (same type -> same schema)."""
    store = _object_schemas.get(py_type)
    if store is None:
        store = type(f"{py_type.__name__}Store", (ObjectStore,), {"wraps": py_type})
        _object_schemas[py_type] = store
    return store


_object_schemas: dict[type, type[Component]] = {}


# Where the types of values that can never be components come from: a plain class of the
# user's is a component (stored as objects), a builtin or NumPy value is a mistake (a None, a
# stray float, a list where a Component value was meant) that would make a `NoneTypeStore`.
_VALUE_MODULES = ("builtins", "numpy", "decimal", "fractions")


def not_a_component(value: Any) -> str | None:
    """What `value` is, in words, when it cannot be a component (None when it can): a class
    instead of an instance, or a builtin or NumPy value (None, str, bytes, numbers, bools,
    lists, tuples, dicts, sets, arrays)."""
    if isinstance(value, Component):
        return None
    if isinstance(value, type):
        return f"the class {value.__name__}"
    module = type(value).__module__.partition(".")[0]
    if module not in _VALUE_MODULES:
        return None
    if value is None:
        return "None"
    if isinstance(value, np.ndarray):
        return f"a NumPy array of shape {value.shape}"
    name = type(value).__name__
    return f"{'an' if name[0] in 'aeiou' else 'a'} {name} ({_preview(value)})"


def refuse_non_component(value: Any, call: str, position: int) -> None:
    """TypeError naming the argument (`call`'s 1-based `position`) when `value` cannot be a
    component."""
    what = not_a_component(value)
    if what is None:
        return
    if isinstance(value, type):
        raise TypeError(
            f"{call}: argument {position} is {what}: pass a component value such as {value.__name__}(), "
            "not the class itself"
        )
    raise TypeError(
        f"{call}: argument {position} is {what}, not a component: pass a Component value such as "
        "Transform(), or an instance of a class of your own"
    )


def schema_of(t: Any) -> type[Component]:
    """The storage schema for a component type; plain Python classes map to an object column."""
    if isinstance(t, type):
        return t if issubclass(t, Component) else object_component(t)
    raise TypeError(f"expected a component type (a class), got {t!r}")


def closure(types: set[type[Component]]) -> set[type[Component]]:
    """`types` plus every component they require, transitively."""
    out = set(types)
    todo = list(types)
    while todo:
        for req in todo.pop().required:
            if req not in out:
                out.add(req)
                todo.append(req)
    return out
