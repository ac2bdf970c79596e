"""The Vulkan layer: one module per Vulkan concept (instance, device, memory, images,
descriptors, pipelines, frame sync, render targets). Nothing here knows about the ECS."""
