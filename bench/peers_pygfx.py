"""The scaling workload in pygfx (bench/peers.py's peer): the same cubes, knots, camera and lights
as the engine's scaling scene, drawn by pygfx on a 640x360 offscreen canvas.

The numbers come from the engine's own scene: `scene_numbers` builds demos/scaling.py into a
World (CPU only, no device) and reads its columns back, so both sides start from the same seed's
positions, rotations, scales, velocities, angular velocities, materials and knots (0.1% of the
entities, the same mesh as the engine's), the same camera and the same 6 orbiting point lights.

A frame: every entity moved and spun in NumPy by the engine's own NumPy reference kernels
(maths/transform.py's integrate_linear_numpy and integrate_angular_numpy, what MotionSystem
computes), the lights moved along their orbits (systems/orbit.py's orbit_step_numpy), pygfx
updated, the scene rendered and the canvas read back: `OffscreenRenderCanvas.draw()` copies the
frame into a mapped buffer and waits for the map (a sync download), so the GPU has finished the
frame when it returns.

Variants:
- "instanced": one `gfx.InstancedMesh` per mesh (cubes, knots), its per-instance matrices
  written from NumPy each frame and uploaded whole (`update_full`). pygfx has no per-instance
  material: every instance gets one Phong material (the palette's first, grey).
- "objects": one `gfx.Mesh` per entity (shared geometry, one of the palette's six Phong
  materials as the engine's scene assigns them), its local position and rotation set from
  Python each frame, as a pygfx program does for objects that move on their own.

The renderer is set to draw what the engine draws: `pixel_scale=1` (pygfx's default of 2 renders
4x the pixels and filters down), no post-process anti-aliasing (`ppaa="none"`), no depth sorting
of objects (`sort_objects=False`; everything is opaque), back faces culled (`side="front"`).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass
from typing import Any

import numpy as np

DT = 1.0 / 60.0
WIDTH, HEIGHT = 640, 360
CLEAR_COLOR = (0.02, 0.02, 0.03)  # the engine Renderer's default
RENDERER = {"pixel_scale": 1, "ppaa": "none", "sort_objects": False}  # see the docstring


@dataclass
class SceneNumbers:
    """The engine scaling scene's numbers, as NumPy arrays (float64 unless said)."""

    position: np.ndarray  # (n, 3)
    rotation: np.ndarray  # (n, 4) unit quaternions (x, y, z, w)
    scale: np.ndarray  # (n, 3)
    linear: np.ndarray  # (n, 3) units/s
    angular: np.ndarray  # (n, 3) world-frame axis * rad/s
    knot: np.ndarray  # (n,) bool: the entity draws the torus knot
    material: np.ndarray  # (n,) palette index 0-5
    meshes: tuple[Any, Any]  # the engine's MeshData of the cube and the knot
    camera_position: np.ndarray  # (3,)
    camera_rotation: np.ndarray  # (4,)
    fov_y: float  # radians
    near: float
    orbit: dict[str, np.ndarray]  # the 6 lights' Orbit columns
    light_color: np.ndarray  # (6, 3)
    light_intensity: np.ndarray  # (6,)

    def __len__(self) -> int:
        return len(self.position)


def scene_numbers(entities: int) -> SceneNumbers:
    """demos/scaling.py's scene of `entities` (the seed it always uses), read out of a World."""
    from ecs_engine import World
    from ecs_engine.components import AngularVelocity, Camera, Mesh, Orbit, PointLight, Transform, Velocity
    from ecs_engine.demos import scaling

    world, meshes = World(), []

    def add_mesh(mesh: Any) -> int:
        meshes.append(mesh)
        return len(meshes) - 1

    scaling.build(world, add_mesh, entities=entities)
    moving = world.query(Transform, Velocity, AngularVelocity, Mesh, write=())
    camera = world.query(Transform, Camera, write=())
    lights = world.query(Transform, Orbit, PointLight, write=())
    return SceneNumbers(
        position=moving.column(Transform.position),
        rotation=moving.column(Transform.rotation),
        scale=moving.column(Transform.scale),
        linear=moving.column(Velocity.linear),
        angular=moving.column(AngularVelocity.angular),
        knot=moving.column(Mesh.handle) == 1,  # build adds the cube first, then the knot
        material=moving.column(Mesh.material).astype(np.int64),
        meshes=(meshes[0], meshes[1]),
        camera_position=camera.column(Transform.position)[0],
        camera_rotation=camera.column(Transform.rotation)[0],
        fov_y=float(camera.column(Camera.fov_y)[0]),
        near=float(camera.column(Camera.near)[0]),
        orbit={name: lights.column(getattr(Orbit, name)) for name in ("center", "radius", "angular_speed", "phase")}
        | {"height": lights.column(Orbit.height)},
        light_color=lights.column(PointLight.color),
        light_intensity=lights.column(PointLight.intensity),
    )


def check_available() -> str | None:
    """None when pygfx, wgpu and rendercanvas import; else the name that failed."""
    for name in ("wgpu", "rendercanvas.offscreen", "pygfx"):
        try:
            __import__(name)
        except ImportError:
            return name.split(".")[0]
    return None


def adapter_info() -> dict[str, Any]:
    """The adapter wgpu picks (pygfx draws on it); RuntimeError when there is none."""
    import wgpu

    try:
        adapter = wgpu.gpu.request_adapter_sync(power_preference="high-performance")
    except Exception as exc:  # wgpu raises its own error types, by backend
        raise RuntimeError(f"wgpu found no GPU adapter ({exc})") from exc
    if adapter is None:
        raise RuntimeError("wgpu found no GPU adapter")
    info = dict(adapter.info)
    return {key: info.get(key) for key in ("vendor", "device", "description", "adapter_type", "backend_type")}


def versions() -> dict[str, str]:
    import pygfx
    import rendercanvas
    import wgpu

    return {"pygfx": pygfx.__version__, "wgpu": wgpu.__version__, "rendercanvas": rendercanvas.__version__}


class Canvas:
    """One offscreen canvas and renderer for a whole run (pygfx shares one wgpu device)."""

    def __init__(self) -> None:
        import pygfx as gfx
        from rendercanvas.offscreen import OffscreenRenderCanvas

        self.canvas = OffscreenRenderCanvas(size=(WIDTH, HEIGHT), pixel_ratio=1)
        self.renderer = gfx.WgpuRenderer(self.canvas, **RENDERER)
        self.last: np.ndarray | None = None  # the last frame read back, (HEIGHT, WIDTH, 4) uint8

    def frame(self, scene: Any, camera: Any) -> None:
        """Render and read the frame back (returns once the GPU has finished it)."""
        self.canvas.request_draw(lambda: self.renderer.render(scene, camera))
        self.last = np.asarray(self.canvas.draw())

    def close(self) -> None:
        self.canvas.close()


def pygfx_fov(fov_y: float, aspect: float) -> float:
    """pygfx's fov (degrees) spans the mean of the view's width and height; the engine's spans
    its height: the pygfx angle that gives the engine's vertical one at this aspect."""
    return math.degrees(2.0 * math.atan(math.tan(fov_y / 2.0) * (1.0 + aspect) / 2.0))


def geometry(mesh: Any) -> Any:
    import pygfx as gfx

    return gfx.Geometry(
        positions=np.ascontiguousarray(mesh.positions, np.float32),
        normals=np.ascontiguousarray(mesh.normals, np.float32),
        indices=np.ascontiguousarray(mesh.indices.reshape(-1, 3), np.int32),
    )


def palette_materials() -> list[Any]:
    """The engine's six default materials as pygfx Phong materials (colour and shininess)."""
    import pygfx as gfx

    from ecs_engine.render.assets.materials import DEFAULT_PALETTE

    return [
        gfx.MeshPhongMaterial(color=(*m.base_color[:3], 1.0), shininess=m.shininess, side="front")
        for m in DEFAULT_PALETTE
    ]


def stage(numbers: SceneNumbers) -> tuple[Any, Any, list[Any]]:
    """The scene (ambient light, 6 point lights) and camera, before any entity is added."""
    import pygfx as gfx

    scene = gfx.Scene()
    scene.add(gfx.Background.from_color(CLEAR_COLOR), gfx.AmbientLight(intensity=0.2))
    lights = []
    for color, intensity in zip(numbers.light_color, numbers.light_intensity):
        light = gfx.PointLight(color=tuple(float(c) for c in color), intensity=float(intensity), decay=2.0)
        scene.add(light)
        lights.append(light)
    aspect = WIDTH / HEIGHT
    camera = gfx.PerspectiveCamera(pygfx_fov(numbers.fov_y, aspect), aspect, depth_range=(numbers.near, 1e5))
    camera.local.position = tuple(numbers.camera_position)
    camera.local.rotation = tuple(numbers.camera_rotation)
    return scene, camera, lights


class Motion:
    """The entities' and lights' state, stepped in NumPy each frame as the engine's systems do."""

    def __init__(self, numbers: SceneNumbers, lights: list[Any]) -> None:
        self.n = numbers
        self.position, self.rotation = numbers.position.copy(), numbers.rotation.copy()
        self.orbit = {k: v.copy() for k, v in numbers.orbit.items()}
        self.lights = lights
        self.light_position = np.zeros((len(lights), 3))

    def step(self) -> None:
        from ecs_engine.maths.transform import integrate_angular_numpy, integrate_linear_numpy
        from ecs_engine.systems.orbit import orbit_step_numpy

        integrate_linear_numpy(self.position, self.n.linear, DT)
        integrate_angular_numpy(self.rotation, self.n.angular, DT)
        o = self.orbit
        orbit_step_numpy(o["center"], o["radius"], o["angular_speed"], o["phase"], o["height"], self.light_position, DT)
        for light, p in zip(self.lights, self.light_position.tolist()):
            light.local.position = p

    def matrices(self, rows: np.ndarray, out: np.ndarray) -> None:
        """The rows' model matrices, transposed as pygfx stores them (column-major), into `out`."""
        from ecs_engine.maths.transform import quat_to_mat3

        linear = quat_to_mat3(self.rotation[rows]) * self.n.scale[rows][:, None, :]
        out[:, :3, :3] = linear.transpose(0, 2, 1)
        out[:, 3, :3] = self.position[rows]


def build_instanced(numbers: SceneNumbers) -> tuple[Any, Any, Any]:
    """(scene, camera, per-frame update) for the instanced variant."""
    import pygfx as gfx

    scene, camera, lights = stage(numbers)
    motion, material = Motion(numbers, lights), palette_materials()[0]
    parts = []
    for mesh, rows in zip(numbers.meshes, (np.flatnonzero(~numbers.knot), np.flatnonzero(numbers.knot))):
        if len(rows):
            instanced = gfx.InstancedMesh(geometry(mesh), material, len(rows))
            instanced.frustum_culled = False  # the instances' box is the whole scene's
            scene.add(instanced)
            parts.append((rows, instanced.instance_buffer))
            matrix = instanced.instance_buffer.data["matrix"]
            matrix[:, 3, 3] = 1.0

    def update() -> None:
        motion.step()
        for rows, buffer in parts:
            motion.matrices(rows, buffer.data["matrix"])
            buffer.update_full()

    update()
    return scene, camera, update


def build_objects(numbers: SceneNumbers) -> tuple[Any, Any, Any]:
    """(scene, camera, per-frame update) for the one-object-per-entity variant."""
    import pygfx as gfx

    scene, camera, lights = stage(numbers)
    motion, materials = Motion(numbers, lights), palette_materials()
    shapes = [geometry(mesh) for mesh in numbers.meshes]
    objects = []
    for knot, material, scale in zip(numbers.knot.tolist(), numbers.material.tolist(), numbers.scale.tolist()):
        obj = gfx.Mesh(shapes[knot], materials[material])
        obj.local.scale = scale
        objects.append(obj)
    scene.add(*objects)

    def update() -> None:
        motion.step()
        for obj, p, q in zip(objects, motion.position.tolist(), motion.rotation.tolist()):
            obj.local.position = p
            obj.local.rotation = q

    update()
    return scene, camera, update


BUILDERS = {"instanced": build_instanced, "objects": build_objects}


def measure(
    canvas: Canvas, numbers: SceneNumbers, variant: str, frames: int, warmup: int, budget_s: float
) -> dict[str, Any]:
    """Wall ms a frame (the median, and its two parts) over `frames` frames after `warmup`;
    frames past `budget_s` seconds (warm-up included) stop the timing early, after 3 timed
    frames at least, and the row says how many it timed. A scene pygfx cannot make gives
    {"skipped": why}: pygfx 0.17 gives every instance an object id and refuses more than
    1,000,000 ids, so the 1M scene."""
    t0 = time.perf_counter()
    try:
        scene, camera, update = BUILDERS[variant](numbers)
    except RuntimeError as exc:  # pygfx: "Max number of objects reached."
        why = f"{exc} (pygfx gives every instance an object id, 1,000,000 at most)"
        return {"skipped": f"pygfx could not build it: {why}"}
    build_s = time.perf_counter() - t0
    wall, update_ms, render_ms = [], [], []
    start = time.perf_counter()
    for i in range(warmup + frames):
        t0 = time.perf_counter()
        update()
        t1 = time.perf_counter()
        canvas.frame(scene, camera)
        t2 = time.perf_counter()
        if i >= warmup:
            wall.append((t2 - t0) * 1e3)
            update_ms.append((t1 - t0) * 1e3)
            render_ms.append((t2 - t1) * 1e3)
            if len(wall) >= 3 and t2 - start > budget_s:
                break
    return {
        "wall_ms": float(np.median(wall)),
        "update_ms": float(np.median(update_ms)),
        "render_ms": float(np.median(render_ms)),
        "frames": len(wall),
        "stopped_early": len(wall) < frames,
        "build_s": round(build_s, 3),
    }
