"""The components both engines run in the ECS benchmark, and the worlds built from them.

esper's benchmark components (E*, plain classes) and the same as native schemas (N*) make the
query and dynamic-world workloads' world of "enemies" and "things" (`populate_esper`,
`populate_native`, shared by both workloads). The transform frame and spawn workloads give
esper plain-Python transform components with __slots__ (P*) and two processors that do per
entity in Python what MotionSystem and TransformSystem do in the engine, so that both engines
make the same matrices.
"""

from __future__ import annotations

import math
from typing import Any

import numpy as np

from ecs_engine import Component, Field, World

from .ecs_engines import esper


# ============================================================== components
# esper's benchmark components (plain classes), x/y settable so sums can be checked.
class EPosition:
    def __init__(self, x: float = 0.0, y: float = 0.0) -> None:
        self.x = x
        self.y = y


class EVelocity:
    def __init__(self, x: float = 0.0, y: float = 0.0) -> None:
        self.x = x
        self.y = y


class EHealth:
    def __init__(self) -> None:
        self.hp = 100


class ECommand:
    def __init__(self) -> None:
        self.attack = False
        self.defend = True


class EDamageable:
    def __init__(self) -> None:
        self.defense = 45


# The same as native schemas.
class NPosition(Component):
    x = Field(np.float64)
    y = Field(np.float64)


class NVelocity(Component):
    x = Field(np.float64)
    y = Field(np.float64)


class NHealth(Component):
    hp = Field(np.int32, default=100)


class NCommand(Component):
    attack = Field(np.bool_, default=False)
    defend = Field(np.bool_, default=True)


class NDamageable(Component):
    defense = Field(np.int32, default=45)


# Plain-Python transform components for the esper frame (fastest honest plain Python: slots).
class PTransform:
    __slots__ = ("x", "y", "z", "qx", "qy", "qz", "qw", "sx", "sy", "sz")  # noqa: RUF023 - constructor order

    def __init__(
        self,
        x: float = 0.0,
        y: float = 0.0,
        z: float = 0.0,
        qx: float = 0.0,
        qy: float = 0.0,
        qz: float = 0.0,
        qw: float = 1.0,
        sx: float = 1.0,
        sy: float = 1.0,
        sz: float = 1.0,
    ) -> None:
        self.x, self.y, self.z = x, y, z
        self.qx, self.qy, self.qz, self.qw = qx, qy, qz, qw
        self.sx, self.sy, self.sz = sx, sy, sz


class PVelocity:
    __slots__ = ("x", "y", "z")

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> None:
        self.x, self.y, self.z = x, y, z


class PAngularVelocity:
    __slots__ = ("x", "y", "z")

    def __init__(self, x: float = 0.0, y: float = 0.0, z: float = 0.0) -> None:
        self.x, self.y, self.z = x, y, z


class PMesh:
    __slots__ = ("handle", "material")

    def __init__(self, handle: int = 0, material: int = 0) -> None:
        self.handle, self.material = handle, material


_IDENTITY4 = (1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0)
_IDENTITY3 = (1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0)


class PModelMatrix:
    __slots__ = ("model", "normal")

    def __init__(self) -> None:
        self.model = _IDENTITY4
        self.normal = _IDENTITY3


_ProcessorBase: type = esper.Processor if esper is not None else object


class MotionProcessor(_ProcessorBase):  # type: ignore[misc, valid-type]
    """MotionSystem in plain Python: linear step, then the exact constant-rate quaternion step."""

    def __init__(self, api: Any) -> None:
        self.api = api

    def process(self, dt: float) -> None:
        get_components = self.api.get_components
        for _, (t, v) in get_components(PTransform, PVelocity):
            t.x += v.x * dt
            t.y += v.y * dt
            t.z += v.z * dt
        sqrt, sin, cos = math.sqrt, math.sin, math.cos
        for _, (t, a) in get_components(PTransform, PAngularVelocity):
            ax, ay, az = a.x, a.y, a.z
            rate = sqrt(ax * ax + ay * ay + az * az)
            half = 0.5 * rate * dt
            k = sin(half) / rate if rate > 1e-12 else 0.5 * dt
            dx, dy, dz, dw = ax * k, ay * k, az * k, cos(half)
            x, y, z, w = t.qx, t.qy, t.qz, t.qw
            nx = dw * x + dx * w + dy * z - dz * y
            ny = dw * y - dx * z + dy * w + dz * x
            nz = dw * z + dx * y - dy * x + dz * w
            nw = dw * w - dx * x - dy * y - dz * z
            norm = sqrt(nx * nx + ny * ny + nz * nz + nw * nw)
            if norm == 0.0:
                norm = 1.0
            t.qx = nx / norm
            t.qy = ny / norm
            t.qz = nz / norm
            t.qw = nw / norm


class TransformProcessor(_ProcessorBase):  # type: ignore[misc, valid-type]
    """TransformSystem in plain Python: camera-relative model matrix and cofactor normal matrix."""

    def __init__(self, api: Any, origin: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> None:
        self.api = api
        self.origin = origin

    def process(self, dt: float) -> None:
        ox, oy, oz = self.origin
        for _, (t, m) in self.api.get_components(PTransform, PModelMatrix):
            x, y, z, w = t.qx, t.qy, t.qz, t.qw
            n2 = x * x + y * y + z * z + w * w
            s = 2.0 / n2 if n2 > 0.0 else 0.0
            xs, ys, zs = x * s, y * s, z * s
            wx, wy, wz = w * xs, w * ys, w * zs
            xx, xy, xz = x * xs, x * ys, x * zs
            yy, yz, zz = y * ys, y * zs, z * zs
            r00 = 1.0 - (yy + zz)
            r01 = xy - wz
            r02 = xz + wy
            r10 = xy + wz
            r11 = 1.0 - (xx + zz)
            r12 = yz - wx
            r20 = xz - wy
            r21 = yz + wx
            r22 = 1.0 - (xx + yy)
            sx, sy, sz = t.sx, t.sy, t.sz
            m.model = (
                r00 * sx,
                r01 * sy,
                r02 * sz,
                t.x - ox,
                r10 * sx,
                r11 * sy,
                r12 * sz,
                t.y - oy,
                r20 * sx,
                r21 * sy,
                r22 * sz,
                t.z - oz,
                0.0,
                0.0,
                0.0,
                1.0,
            )
            c0 = sy * sz
            c1 = sx * sz
            c2 = sx * sy
            a0 = c0 if c0 >= 0.0 else -c0
            a1 = c1 if c1 >= 0.0 else -c1
            a2 = c2 if c2 >= 0.0 else -c2
            peak = a0 if a0 >= a1 else a1
            if a2 > peak:
                peak = a2
            if peak > 0.0:
                f = 1.0 / peak
                if sx * sy * sz < 0.0:
                    f = -f
            else:
                f = 0.0
            c0 *= f
            c1 *= f
            c2 *= f
            m.normal = (r00 * c0, r01 * c1, r02 * c2, r10 * c0, r11 * c1, r12 * c2, r20 * c0, r21 * c1, r22 * c2)


# ============================================================== esper's benchmark world
def populate_esper(api: Any, n: int, xs: list[float]) -> list[int]:
    create = api.create_entity
    ids = []
    for i in range(n // 2):
        ids.append(create(EPosition(xs[2 * i]), EVelocity(), EHealth(), ECommand()))
        ids.append(create(EPosition(xs[2 * i + 1]), EHealth(), EDamageable()))
    return ids


def populate_native(world: World, n: int, xs: np.ndarray) -> list[int]:
    enemies = world.spawn_batch(
        n // 2, NPosition(x=xs[0 : 2 * (n // 2) : 2], y=0.0), NVelocity(), NHealth(), NCommand()
    )
    things = world.spawn_batch(n // 2, NPosition(x=xs[1 : 2 * (n // 2) : 2], y=0.0), NHealth(), NDamageable())
    order = np.empty(2 * (n // 2), dtype=np.int64)
    order[0::2] = enemies
    order[1::2] = things
    return order.tolist()
