"""gpu/owned.py: a scope destroys what it owns, last made first, once each, even when one of the
destroys fails; with a real device, what it creates goes with it (conftest: no validation
message, no memory left allocated)."""

from __future__ import annotations

import pytest
from gpu_context import shared_device

from ecs_engine.gpu.owned import Owned


class FakeDevice:
    vk = None
    handle = None
    objects_version = 0


def test_destroys_in_reverse_order_once():
    gone = []
    owned = Owned(FakeDevice())
    for name in "abc":
        owned.add(name, lambda name=name: gone.append(name))
    assert len(owned) == 3 and owned.made == 3
    owned.destroy()
    owned.destroy()
    assert gone == ["c", "b", "a"] and len(owned) == 0


def test_objects_with_a_destroy_method_and_release_of_one():
    class Thing:
        def __init__(self):
            self.destroyed = 0

        def destroy(self):
            self.destroyed += 1

    owned = Owned(FakeDevice())
    a, b = owned.add(Thing()), owned.add(Thing())
    owned.release(a)
    assert a.destroyed == 1 and len(owned) == 1
    with pytest.raises(ValueError, match="does not own"):
        owned.release(a)
    owned.destroy()
    assert (a.destroyed, b.destroyed) == (1, 1)


def test_a_failing_destroy_does_not_stop_the_others():
    gone = []
    owned = Owned(FakeDevice())
    owned.add("a", lambda: gone.append("a"))
    owned.add("bad", lambda: 1 / 0)
    owned.add("c", lambda: gone.append("c"))
    with pytest.raises(ZeroDivisionError):
        owned.destroy()
    assert gone == ["c", "a"]
    owned.destroy()  # nothing left to fail
    assert gone == ["c", "a"]


def test_a_block_that_raises_leaves_nothing_made():
    gone = []
    with pytest.raises(RuntimeError), Owned(FakeDevice()) as owned:
        owned.add("a", lambda: gone.append("a"))
        raise RuntimeError("half made")
    assert gone == ["a"]


def test_vulkan_objects_it_creates_are_destroyed_with_it():
    device = shared_device()
    vk = device.vk
    version = device.objects_version
    with Owned(device) as owned:
        image = owned.create(
            "Image",
            vk.VkImageCreateInfo(
                imageType=vk.VK_IMAGE_TYPE_2D,
                format=vk.VK_FORMAT_R8G8B8A8_UNORM,
                extent=vk.VkExtent3D(4, 4, 1),
                mipLevels=1,
                arrayLayers=1,
                samples=1,
                tiling=vk.VK_IMAGE_TILING_OPTIMAL,
                usage=vk.VK_IMAGE_USAGE_SAMPLED_BIT,
                sharingMode=vk.VK_SHARING_MODE_EXCLUSIVE,
                initialLayout=vk.VK_IMAGE_LAYOUT_UNDEFINED,
            ),
        )
        req = vk.vkGetImageMemoryRequirements(device.handle, image)
        memory = owned.allocation(device.allocator.allocate(req, "device", "image"))
        vk.vkBindImageMemory(device.handle, image, memory.memory, memory.offset)
        owned.create("Sampler", vk.VkSamplerCreateInfo(magFilter=vk.VK_FILTER_LINEAR, minFilter=vk.VK_FILTER_LINEAR))
        assert len(owned) == 3 and device.objects_version > version
    assert len(owned) == 0  # the image, its memory and the sampler: validation reports leaks at the end
