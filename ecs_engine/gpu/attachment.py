"""The attachment description every render pass here writes the same way."""

from __future__ import annotations

from typing import Any


def attachment(vk: Any, fmt: int, samples: int, load: int, store: int, final: int, initial: int = 0) -> Any:
    """An attachment without stencil, its contents undefined when the pass begins unless loaded
    from `initial` (VK_IMAGE_LAYOUT_UNDEFINED is 0)."""
    return vk.VkAttachmentDescription(
        format=fmt,
        samples=samples,
        loadOp=load,
        storeOp=store,
        stencilLoadOp=vk.VK_ATTACHMENT_LOAD_OP_DONT_CARE,
        stencilStoreOp=vk.VK_ATTACHMENT_STORE_OP_DONT_CARE,
        initialLayout=initial,
        finalLayout=final,
    )
