"""Images the engine owns, shown in ImGui (`imgui.image(imgui.ImTextureRef(tex_id), size)`): the
editor's shadow map thumbnails (app/editor_lights.py). Each registered image view gets a
descriptor set of the ImGui renderer's layout (imgui_pass.py: one combined image sampler) and an
ImGui texture id; the image, its view and sampler stay the caller's, and must be in `layout`
whenever the overlay draws (after the tone map, or in the direct form its rendering after the scene's).

A view may go away under a UI already built (the shadow maps are made anew, larger, between the
editor's build and the overlay's draw): the caller passes `alive`, asked at the start of every
overlay frame; an image no longer alive is dropped, and commands naming an id this backend does
not know are not drawn. A dropped image's set goes back to the pool only once no frame in
flight can still read it (frames_in_flight overlay frames later): a set is rewritten when reused.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ...gpu.descriptors import write_images


@dataclass
class UserImage:
    descriptor_set: Any
    set_array: Any  # VkDescriptorSet[1] for raw calls
    alive: Callable[[], bool] | None


class UserImages:
    def __init__(self, vk: Any, device: Any, allocate_set: Callable[[], Any], release_set: Callable[[Any], None]):
        self.vk, self.device = vk, device
        self._allocate, self._release = allocate_set, release_set
        self._images: dict[int, UserImage] = {}
        self._retired: list[tuple[int, Any]] = []  # (the overlay frame it was dropped in, its set)
        self._frame = 0  # overlay frames begun
        self._changed = False  # an image went away since the last frame began

    def __len__(self) -> int:
        return len(self._images)

    def __contains__(self, tex_id: int) -> bool:
        return tex_id in self._images

    def get(self, tex_id: int) -> UserImage | None:
        return self._images.get(tex_id)

    def register(
        self, tex_id: int, view: Any, sampler: Any, layout: int, alive: Callable[[], bool] | None = None
    ) -> None:
        vk = self.vk
        descriptor_set = self._allocate()
        write_images(
            self.device,
            descriptor_set,
            0,
            [vk.VkDescriptorImageInfo(sampler=sampler, imageView=view, imageLayout=layout)],
        )
        self._images[tex_id] = UserImage(descriptor_set, vk.ffi.new("VkDescriptorSet[1]", [descriptor_set]), alive)

    def update(self, tex_id: int, view: Any, sampler: Any, layout: int) -> None:
        """Name another view under the same id (its set rewritten in place): only while no frame
        in flight reads the set (after `device.wait_idle()`, as a resize already waits)."""
        image = self._images[tex_id]
        info = self.vk.VkDescriptorImageInfo(sampler=sampler, imageView=view, imageLayout=layout)
        write_images(self.device, image.descriptor_set, 0, [info])

    def unregister(self, tex_id: int) -> None:
        """The image is not drawn from the next overlay frame on (unknown ids are ignored)."""
        image = self._images.pop(tex_id, None)
        if image is not None:
            self._retired.append((self._frame, image.descriptor_set))
            self._changed = True

    def begin_frame(self, frames_in_flight: int) -> bool:
        """At the start of an overlay frame (its slot's fence waited on): sets dropped long enough
        ago go back to the pool, images no longer alive are dropped; True when any image went away
        since the last frame (draws made before then may name it)."""
        keep = []
        for dropped, descriptor_set in self._retired:
            if self._frame - dropped >= frames_in_flight:
                self._release(descriptor_set)
            else:
                keep.append((dropped, descriptor_set))
        self._retired = keep
        for tex_id, image in list(self._images.items()):
            if image.alive is not None and not image.alive():
                self.unregister(tex_id)
        self._frame += 1
        changed, self._changed = self._changed, False
        return changed

    def clear(self) -> None:
        """Forget every image (the renderer destroys the sets with their pools)."""
        self._images.clear()
        self._retired.clear()
