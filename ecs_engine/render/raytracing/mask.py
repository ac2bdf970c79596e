"""The ray-traced shadows' mask (render/raytracing/shadows.py): per pixel and shadow-casting light, the
fraction of its rays that reached the light, four lights a layer (RGBA8, one per channel). The
deferred lighting reads it (a storage image, so both stay in the GENERAL layout); made with the
target's attachments, cleared to 1 (lit) so a frame that traces nothing reads no shadow."""

from __future__ import annotations

from typing import Any

from ...gpu.image_clear import clear_once
from ...gpu.memory import Image
from ..layouts import MAX_RAY_LIGHTS

LAYERS = MAX_RAY_LIGHTS // 4


class ShadowMask:
    def __init__(self, device: Any, width: int, height: int) -> None:
        vk = device.vk
        self.device = device
        self.width, self.height = width, height
        usage = vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT
        self.image = Image(
            device, width, height, vk.VK_FORMAT_R8G8B8A8_UNORM, usage, vk.VK_IMAGE_ASPECT_COLOR_BIT, layers=LAYERS
        )
        try:
            self._clear()
        except BaseException:
            self.image.destroy()
            raise

    @property
    def view(self) -> Any:
        return self.image.view

    def _clear(self) -> None:
        vk = self.device.vk
        general, shaders = vk.VK_IMAGE_LAYOUT_GENERAL, vk.VK_PIPELINE_STAGE_COMPUTE_SHADER_BIT
        access = vk.VK_ACCESS_SHADER_READ_BIT
        clear_once(
            self.device,
            self.image.handle,
            depth=False,
            layers=LAYERS,
            value=1.0,
            layout=general,
            readers=shaders,
            read_access=access,
        )

    def destroy(self) -> None:
        self.image.destroy()
