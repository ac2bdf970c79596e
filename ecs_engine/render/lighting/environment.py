"""The GPU side of the world's Environment (components/environment.py): its cube map with a
GGX-prefiltered mip chain (half floats, sampled trilinearly; environment_prefilter.py), and what
the frame's globals carry: the intensity, the mip level that holds roughness 1 (roughness picks a
level), whether it lights the ambient, and its diffuse light as 9 spherical harmonics
(environment_maps.py does the CPU work). Prefiltering runs on the job pool when given one.

Without an Environment a black 1-texel cube stays bound (the shaders are compiled without
FEATURE_ENVIRONMENT then and never read it). A new Environment object is loaded when the frame
first sees it, unless only its intensity, sky or ambient changed (the same source object and
size); the device is waited for before the old image goes.
"""

from __future__ import annotations

from typing import Any

import numpy as np

from ...components.environment import Environment
from ...gpu.array_image import ArrayImage, clamped_sampler
from ...gpu.device import Device
from ...gpu.owned import Owned
from ...jobs import JobPool
from .environment_maps import cube_mips, irradiance_sh9, load_cube
from .environment_prefilter import ggx_prefiltered_mips, roughness_levels


def _chains(mips: list[np.ndarray]) -> list[list[np.ndarray]]:
    """Per face, its levels as RGBA16F texels (alpha 1), for ArrayImage.upload."""
    chains: list[list[np.ndarray]] = [[] for _ in range(6)]
    for level in mips:
        rgba = np.ones((*level.shape[:3], 4), np.float16)
        rgba[..., :3] = np.minimum(level, 65504.0)
        for face in range(6):
            chains[face].append(rgba[face])
    return chains


class EnvironmentMap:
    def __init__(self, device: Device) -> None:
        self.device = device
        self.owned = Owned(device)  # the sampler, then the image (replaced by each new source)
        self.source: Environment | None = None  # what the image holds
        self.image: ArrayImage | None = None
        self.irradiance = np.zeros((9, 3), np.float32)
        try:
            sampler = self.sampler = clamped_sampler(device)
            self.owned.add(sampler, lambda: device.vk.vkDestroySampler(device.handle, sampler, None))
            self._upload(cube_mips(np.zeros((6, 1, 1, 3), np.float32)))
        except BaseException:
            self.destroy()
            raise

    @property
    def active(self) -> bool:
        """Whether the world has an Environment (the shaders then read it)."""
        return self.source is not None

    @property
    def sky(self) -> bool:
        """Whether the sky is drawn behind the scene."""
        return self.source is not None and self.source.sky

    def sync(self, env: Environment | None, jobs: JobPool | None = None) -> bool:
        """Load the frame's Environment (FrameData.environment, the world's as extracted) when
        it is new; True when the bound image changed (the frame sets must name it again). A
        source that cannot be loaded raises UsageError and leaves the previous one bound."""
        if env is self.source:
            return False
        old = self.source
        if env is not None and old is not None and env.source is old.source and env.size == old.size:
            self.source = env  # intensity, sky or ambient changed (the editor): the same image
            return False
        if env is None:
            mips, irradiance = cube_mips(np.zeros((6, 1, 1, 3), np.float32)), np.zeros((9, 3), np.float32)
        else:
            faces = load_cube(env.source, env.size)
            mips = ggx_prefiltered_mips(faces, map_blocks=jobs.map if jobs is not None else None)
            irradiance = irradiance_sh9(faces)
        self.device.wait_idle()  # frames in flight sample the old image
        self._upload(mips)
        self.source, self.irradiance = env, np.asarray(irradiance, np.float32)
        return True

    def _upload(self, mips: list[np.ndarray]) -> None:
        image = ArrayImage(self.device, mips[0].shape[1], 6, cube=True)
        try:
            image.upload(_chains(mips))
        except BaseException:
            image.destroy()
            raise
        if self.image is not None:
            self.owned.release(self.image)
        self.image = self.owned.add(image)

    def image_info(self) -> Any:
        vk = self.device.vk
        assert self.image is not None
        return vk.VkDescriptorImageInfo(
            sampler=self.sampler,
            imageView=self.image.cube_view,
            imageLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
        )

    def globals(self) -> tuple[tuple[float, float, float, float], np.ndarray]:
        """GLOBALS.environment and GLOBALS.irradiance (9 rows of rgb, 0)."""
        env = self.source
        assert self.image is not None
        rows = np.zeros((9, 4), np.float32)
        rows[:, :3] = self.irradiance
        if env is None:
            return (0.0, 0.0, 0.0, 0.0), rows
        return (env.intensity, float(roughness_levels(self.image.levels)), 1.0 if env.ambient else 0.0, 0.0), rows

    def destroy(self) -> None:
        self.owned.destroy()
        self.image = self.sampler = None
