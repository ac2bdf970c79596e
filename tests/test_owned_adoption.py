"""Classes under render/ and gpu/ own their GPU objects through gpu/owned.py's `Owned` scope
instead of a `destroy` that names each handle: a scan of the sources, and what the scope buys
(destroyed twice: harmless; a constructor failing half-way: nothing left), counted on a device
whose binding counts each object made and destroyed."""

from __future__ import annotations

import ast
from collections import Counter
from pathlib import Path
from typing import Any

import pytest
from gpu_context import shared_device

import ecs_engine

PACKAGE = Path(ecs_engine.__file__).resolve().parent  # the installed package (the GPU host runs tests from a copy)

# Files other helpers are converting in this session (their destroys still name handles).
NOT_YET = {
    "render/frame/output_passes.py",
    "render/passes/output_graph.py",
    "render/passes/oit.py",
    "render/passes/light_billboards.py",
    "render/passes/sky.py",
    "render/passes/set_aside.py",
    "render/ui/imgui_pass.py",
    "render/draw/chunk_paths.py",
    "render/draw/indirect_path.py",
    "render/lighting/deferred.py",
    "render/raytracing/shadows.py",
    "render/passes/tone_map.py",
    "render/frame/renderer.py",
    "render/draw/path.py",
    "gpu/scene_attachments.py",
    "gpu/gbuffer.py",
    "gpu/offscreen.py",
    "gpu/swapchain.py",
    "gpu/secondary.py",
    "gpu/pipeline.py",
    "gpu/frames.py",
    "gpu/device.py",
    "gpu/instance.py",
    "gpu/allocator.py",
}

# The leaf wrappers: each owns one handle (a buffer: one handle and its memory), and its destroy
# is that one call; a scope would only wrap it.
ONE_HANDLE = {
    ("gpu/descriptors.py", "DescriptorSetLayout"),
    ("gpu/descriptors.py", "DescriptorPool"),
    ("gpu/pipeline_cache.py", "PipelineCache"),
    ("gpu/memory.py", "Buffer"),
}


def _destroys_by_hand(source: str) -> dict[str, list[str]]:
    """Per class, the vkDestroy*/vkFree* calls made in its destroy (or _destroy*/_release*)."""
    found: dict[str, list[str]] = {}
    for cls in ast.walk(ast.parse(source)):
        if not isinstance(cls, ast.ClassDef):
            continue
        for method in cls.body:
            if not isinstance(method, ast.FunctionDef):
                continue
            if method.name != "destroy" and not method.name.startswith(("_destroy", "_release")):
                continue
            for node in ast.walk(method):
                if isinstance(node, ast.Call):
                    func = node.func
                    name = func.attr if isinstance(func, ast.Attribute) else getattr(func, "id", "")
                    if name.startswith(("vkDestroy", "vkFree")):
                        found.setdefault(cls.name, []).append(f"{method.name}: {name}")
    return found


def test_the_scan_sees_a_hand_written_destroy():
    source = (
        "class A:\n"
        "    def destroy(self):\n"
        "        self.vk.vkDestroySampler(self.h, self.s, None)\n"
        "class B:\n"
        "    def destroy(self):\n"
        "        self.owned.destroy()\n"
    )
    assert _destroys_by_hand(source) == {"A": ["destroy: vkDestroySampler"]}


def test_destroy_methods_leave_handles_to_their_scope():
    offenders = []
    for path in sorted([*(PACKAGE / "render").rglob("*.py"), *(PACKAGE / "gpu").glob("*.py")]):
        name = path.relative_to(PACKAGE).as_posix()
        if name in NOT_YET:
            continue
        for cls, calls in _destroys_by_hand(path.read_text()).items():
            if (name, cls) not in ONE_HANDLE:
                offenders.append(f"{name} {cls}: {', '.join(calls)}")
    assert offenders == [], "destroy these through an Owned scope (gpu/owned.py):\n" + "\n".join(offenders)


def test_the_one_handle_list_names_what_exists():
    for name, cls in ONE_HANDLE:
        assert cls in _destroys_by_hand((PACKAGE / name).read_text()), f"{name} {cls}: gone, or no longer by hand"


# ------------------------------------------------------------------ counted on the device


_MAKE, _UNMAKE = ("vkCreate", "vkAllocate"), ("vkDestroy", "vkFree")


def _kind(function: str) -> str:
    """What a vkCreate*/vkAllocate*/vkDestroy*/vkFree* function makes or unmakes ("" for
    other functions, and for descriptor sets: they go with their pool); pipelines are made in
    lists, command buffers allocated in lists."""
    for verb in (*_MAKE, *_UNMAKE):
        if function.startswith(verb) and "DescriptorSets" not in function:
            kind = function[len(verb) :]
            if kind.endswith("Pipelines"):
                return "Pipeline"
            return kind.removesuffix("s")
    return ""


class CountingVk:
    """The binding, counting live objects by kind; `fail` = (function, n) makes that
    function's n-th call raise before it makes anything."""

    def __init__(self, vk: Any, fail: tuple[str, int] | None = None) -> None:
        self._vk, self._fail = vk, fail
        self.live: Counter[str] = Counter()
        self.calls: Counter[str] = Counter()

    def __getattr__(self, name: str) -> Any:
        found = getattr(self._vk, name)
        kind = _kind(name)
        if not kind or not callable(found):
            return found
        step = 1 if name.startswith(_MAKE) else -1

        def call(*args: Any, **kwargs: Any) -> Any:
            self.calls[name] += 1
            if self._fail == (name, self.calls[name]):
                raise RuntimeError(f"{name} made to fail")
            out = found(*args, **kwargs)
            self.live[kind] += step
            return out

        return call

    def made(self) -> set[str]:
        return {_kind(name) for name in self.calls if name.startswith(_MAKE)}

    def left(self) -> dict[str, int]:
        return {kind: n for kind, n in self.live.items() if n}


class CountingDevice:
    """The shared device seen through CountingVk (everything else is the device's)."""

    def __init__(self, fail: tuple[str, int] | None = None) -> None:
        self._device = shared_device()
        self.vk = CountingVk(self._device.vk, fail)
        self.objects_version = 0

    def __getattr__(self, name: str) -> Any:
        return getattr(self._device, name)


def _shadow_maps(device: Any) -> Any:
    from ecs_engine.gpu.shadow_maps import ShadowMaps

    maps = ShadowMaps(device, 8, 2)
    maps.preview_view(1)  # made later than the rest: owned as well
    return maps


def _bloom(device: Any) -> Any:
    from ecs_engine.render.post.bloom_pipelines import BloomPipelines

    return BloomPipelines(device)


def _denoise(device: Any) -> Any:
    from ecs_engine.render.raytracing.denoise import ShadowDenoise

    return ShadowDenoise(device, 2)


def _image(device: Any) -> Any:
    from ecs_engine.gpu.memory import Image

    vk = device.vk
    return Image(device, 4, 4, vk.VK_FORMAT_R8G8B8A8_UNORM, vk.VK_IMAGE_USAGE_SAMPLED_BIT, vk.VK_IMAGE_ASPECT_COLOR_BIT)


MAKERS = {"shadow maps": _shadow_maps, "bloom pipelines": _bloom, "shadow denoise": _denoise, "image": _image}


@pytest.mark.parametrize("make", MAKERS.values(), ids=MAKERS.keys())
def test_destroyed_twice_destroys_each_object_once(make):
    device = CountingDevice()
    made = make(device)
    assert device.vk.left(), "nothing was counted: the check below could not fail"
    version = device.objects_version
    made.destroy()
    assert device.vk.left() == {}
    assert device.objects_version > version  # frame replay: what was recorded with them is stale
    made.destroy()
    assert device.vk.left() == {}  # nothing destroyed again (a second destroy would count below 0)


# (maker, the call that fails, what was made before it)
HALF_MADE = [
    ("shadow maps", ("vkCreateSampler", 2), {"Image", "ImageView", "Sampler"}),
    ("shadow denoise", ("vkCreateSampler", 1), {"DescriptorSetLayout", "DescriptorPool", "Pipeline"}),
    ("bloom pipelines", ("vkCreateComputePipelines", 3), {"DescriptorSetLayout", "PipelineLayout", "Pipeline"}),
    ("image", ("vkCreateImageView", 1), {"Image"}),
]


@pytest.mark.parametrize(("maker", "fail", "before"), HALF_MADE, ids=[h[0] for h in HALF_MADE])
def test_a_constructor_failing_half_way_leaves_nothing(maker, fail, before):
    device = CountingDevice(fail)
    used = device.allocator.stats()["used_bytes"]
    with pytest.raises(RuntimeError, match="made to fail"):
        MAKERS[maker](device)
    assert before <= device.vk.made()  # the failure came half-way, not first
    assert device.vk.left() == {}
    assert device.allocator.stats()["used_bytes"] == used


def test_light_culling_modes_are_the_config_enum():
    from ecs_engine.errors import UsageError
    from ecs_engine.gpu.descriptors import DescriptorSetLayout
    from ecs_engine.render.config.choices import LightCulling as Mode
    from ecs_engine.render.lighting.clusters import LightCulling, wants_clusters

    device = shared_device()
    layout = DescriptorSetLayout(device, [(0, device.vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, 1)])
    try:
        culling = LightCulling(device, layout.handle, "deferred")
        try:
            assert culling.mode is Mode.DEFERRED and culling.mode == "deferred"
            culling.mode = "loop"  # the editor sets names (target_forms.light_culling)
            assert culling.mode is Mode.LOOP
            with pytest.raises(UsageError, match="clustered"):
                culling.mode = "tiled"
            assert culling.deferred(1) is False
        finally:
            culling.destroy()
            culling.destroy()
    finally:
        layout.destroy()
    assert wants_clusters(Mode.CLUSTERED, False, 1, 0) and wants_clusters("clustered", False, 1, 0)
    assert not wants_clusters(Mode.LOOP, False, 1000, 0)


def test_a_buffer_grown_in_its_scope_replaces_itself_there():
    from ecs_engine.gpu.memory import HOST, Buffer
    from ecs_engine.gpu.owned import Owned

    device = CountingDevice()
    used = device.allocator.stats()["used_bytes"]
    owned = Owned(device)
    small = owned.add(Buffer(device, 64, device.vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT, HOST))
    assert small.grown(32, owned) is small and len(owned) == 1
    big = small.grown(1000, owned)
    assert big is not small and small.handle is None and big.size >= 1000
    assert len(owned) == 1 and device.vk.left() == {"Buffer": 1}
    owned.destroy()
    assert big.handle is None and device.vk.left() == {}
    assert device.allocator.stats()["used_bytes"] == used


class FakeAccelerationFunctions:
    """acceleration_structure.functions(device) where the device traces no rays (lavapipe): a
    structure's create and destroy are counted, its address made up; `fail` makes create fail."""

    def __init__(self, vk: Any, fail: bool = False) -> None:
        self.vk, self.fail, self.live, self.made = vk, fail, 0, 0

    def create(self, device: Any, info: Any, allocator: Any, out: Any) -> int:
        if self.fail:
            return self.vk.VK_ERROR_OUT_OF_DEVICE_MEMORY
        self.made += 1
        self.live += 1
        out[0] = self.vk.ffi.cast("VkAccelerationStructureKHR", 0x1000 + self.made)
        return self.vk.VK_SUCCESS

    def destroy(self, device: Any, handle: Any, allocator: Any) -> None:
        self.live -= 1

    def address(self, device: Any, info: Any) -> int:
        return 0x10000 * self.made


@pytest.mark.parametrize("fail", [False, True], ids=["destroyed twice", "create fails"])
def test_an_acceleration_structure_and_its_buffer_go_together(fail, monkeypatch):
    from ecs_engine.gpu import acceleration_structure
    from ecs_engine.gpu.acceleration_structure import Structure

    device = CountingDevice()
    vk = device.vk
    # a plain storage buffer: this device has neither acceleration structures nor device addresses
    monkeypatch.setattr(acceleration_structure, "_usage", lambda vk, extra: vk.VK_BUFFER_USAGE_STORAGE_BUFFER_BIT)
    fns = device._acceleration_functions = FakeAccelerationFunctions(vk, fail)
    used = device.allocator.stats()["used_bytes"]
    level = vk.lib.VK_ACCELERATION_STRUCTURE_TYPE_BOTTOM_LEVEL_KHR
    if fail:
        with pytest.raises(vk.exception_codes[vk.VK_ERROR_OUT_OF_DEVICE_MEMORY]):
            Structure(device, level, 256)
    else:
        structure = Structure(device, level, 256)
        assert fns.live == 1 and vk.left() == {"Buffer": 1}
        structure.destroy()
        structure.destroy()
        assert structure.handle is None
    assert (fns.live, vk.left()) == (0, {})  # the structure (if made) and its buffer, once each
    assert device.allocator.stats()["used_bytes"] == used
