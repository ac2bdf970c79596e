"""What a pass is and what it declares: the `Pass` base class and the `PassBuilder` its `setup`
declares with (the transients it creates, what it reads and writes, at which mip, how)."""

from __future__ import annotations

from collections.abc import Hashable
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from ...errors import UsageError
from .resources import Access, BufferDesc, ImageDesc, Load, Use

if TYPE_CHECKING:
    from .context import PassContext


class _Unreplayable:
    """The key of a pass that records something new every frame (UI, sorted rows, rays): equal
    to no key, itself included, and `FrameGraph.key()` puts a new object in its place each call
    (a tuple compares its items by identity first, so the sentinel alone would equal itself)."""

    def __eq__(self, other: object) -> bool:
        return False

    def __hash__(self) -> int:
        return id(self)

    def __repr__(self) -> str:
        return "UNREPLAYABLE"


UNREPLAYABLE: Any = _Unreplayable()


class _SetupEachCompile:
    def __repr__(self) -> str:
        return "SETUP_EACH_COMPILE"


#: what `Pass.declares()` returns by default: its setup is called at every compile
SETUP_EACH_COMPILE: Any = _SetupEachCompile()


class Pass:
    """A step of the frame. Subclasses set `name`, declare in `setup` (which only declares: the
    graph calls it at each compile to see whether anything changed) and record in `record`."""

    name: str = ""

    def setup(self, builder: PassBuilder) -> None:
        raise NotImplementedError

    def record(self, cb: Any, ctx: PassContext) -> None:
        raise NotImplementedError

    def declares(self) -> Hashable:
        """What `setup`'s declarations depend on: while this returns an equal value, a compile
        reuses the pass's last declarations without calling `setup` (the per-frame check of a
        graph whose passes did not change is then a comparison per pass). The default,
        SETUP_EACH_COMPILE, calls setup each time. With `FrameGraph.verify_declares` on (the
        tests), setup is called anyway and a declaration that changed under an equal value
        is an error: an incomplete `declares` fails there, not as a stale graph."""
        return SETUP_EACH_COMPILE

    def key(self) -> Hashable:
        """What the recording depends on besides its resources (frame replay compares it);
        `UNREPLAYABLE` (graph.py) for a pass that records something new every frame."""
        return None

    def destroy(self) -> None:
        """Release what the pass made (pipelines...); the graph calls it in its own destroy."""


@dataclass(frozen=True)
class Declared:
    """All a pass's setup declared."""

    creates: tuple[tuple[str, ImageDesc | BufferDesc], ...]
    uses: tuple[Use, ...]
    side_effect: bool


class PassBuilder:
    """Handed to `Pass.setup`; collects its declarations."""

    def __init__(self, pass_name: str) -> None:
        self.pass_name = pass_name
        self._creates: list[tuple[str, ImageDesc | BufferDesc]] = []
        self._uses: list[Use] = []
        self._side_effect = False

    def create(self, name: str, desc: ImageDesc | BufferDesc) -> str:
        """A transient image or buffer the graph allocates (and may alias) for this frame."""
        if not isinstance(desc, (ImageDesc, BufferDesc)):
            raise UsageError(f"pass {self.pass_name!r} creates {name!r} from {desc!r}, not an ImageDesc/BufferDesc")
        if any(n == name for n, _ in self._creates):
            raise UsageError(f"pass {self.pass_name!r} creates {name!r} twice")
        self._creates.append((name, desc))
        return name

    def _check(self, name: str, access: Access, mip: int | None, layer: int | None = None) -> None:
        if not isinstance(access, Access):
            raise UsageError(f"pass {self.pass_name!r}: {access!r} is not an Access")
        if mip is not None and (not isinstance(mip, int) or mip < 0):
            raise UsageError(f"pass {self.pass_name!r}: mip {mip!r} of {name!r} is not a level")
        if layer is not None and (not isinstance(layer, int) or layer < 0):
            raise UsageError(f"pass {self.pass_name!r}: layer {layer!r} of {name!r} is not a layer")

    def read(self, name: str, access: Access, *, mip: int | None = None, layer: int | None = None) -> None:
        """`mip`/`layer`: the one mip level / array layer read (None: all of them)."""
        self._check(name, access, mip, layer)
        if not access.usage.reads:
            raise UsageError(f"pass {self.pass_name!r} reads {name!r} as {access.name}, which writes: use write()")
        if access.usage.writes:
            raise UsageError(f"pass {self.pass_name!r} reads {name!r} as {access.name}, which also writes: use write()")
        self._uses.append(Use(name, access, mip, False, layer=layer))

    def write(
        self,
        name: str,
        access: Access,
        *,
        mip: int | None = None,
        load: Load = Load.DONT_CARE,
        clear: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0),
        layer: int | None = None,
        region: bool = False,
    ) -> None:
        """`region=True`: the pass writes part of it (`begin_rendering(area=...)`, a corner of a
        shadow layer) and the rest is kept: no transition from UNDEFINED, and the pass runs
        after the one that wrote it before (if any); CLEAR then clears the area only."""
        self._check(name, access, mip, layer)
        if not access.usage.writes:
            raise UsageError(f"pass {self.pass_name!r} writes {name!r} as {access.name}, which only reads: use read()")
        if access.usage.reads:  # a read-modify-write keeps what was there
            load = Load.LOAD
        clear_value = tuple(float(c) for c in clear)
        self._uses.append(Use(name, access, mip, True, load, clear_value, layer, bool(region)))  # type: ignore[arg-type]

    def side_effect(self) -> None:
        """The pass is never culled (it reads back, presents or writes outside the graph)."""
        self._side_effect = True

    def declared(self) -> Declared:
        return Declared(tuple(self._creates), tuple(self._uses), self._side_effect)


def declare(p: Pass) -> Declared:
    builder = PassBuilder(p.name)
    p.setup(builder)
    return builder.declared()


class Declarations:
    """The passes' last declarations, each kept with its `declares()` value: a compile asks
    `setup` again only of a pass whose value changed or that has none (see Pass.declares)."""

    def __init__(self) -> None:
        self._kept: dict[int, tuple[Pass, Hashable, Declared]] = {}
        self._last: tuple[list[Pass], tuple, list[tuple[str, Declared]]] | None = None  # the last call's

    def of(self, passes: list[Pass], verify: bool = False) -> tuple[list[tuple[str, Declared]], bool]:
        """Each pass's (name, Declared), and whether any changed since the last call."""
        marks = tuple([p.declares() for p in passes])
        last_call = self._last
        if last_call is not None and not verify and last_call[0] == passes and last_call[1] == marks:
            if SETUP_EACH_COMPILE not in marks:  # the same passes, all declaring as before
                return last_call[2], False
        out, kept, changed = [], self._kept, False
        for p, mark in zip(passes, marks, strict=True):
            last = kept.get(id(p))
            if last is not None and last[0] is not p:  # another pass at a freed one's id
                last = None
            same = last is not None and mark is not SETUP_EACH_COMPILE and last[1] == mark
            if same and not verify:
                out.append((p.name, last[2]))  # type: ignore[index]
                continue
            declared = declare(p)
            if last is None or last[2] != declared:
                if same:
                    raise AssertionError(f"pass {p.name!r} declared anew under the same declares() {mark!r}")
                changed = True
            else:
                declared = last[2]
            kept[id(p)] = (p, mark, declared)
            out.append((p.name, declared))
        if len(kept) > len(passes):  # passes removed: forget them
            alive = {id(p) for p in passes}
            for gone in [k for k in kept if k not in alive]:
                del kept[gone]
        self._last = (list(passes), marks, out)
        return out, changed
