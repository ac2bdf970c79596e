"""From the world to the GPU: frame extraction, the renderer, its render paths and passes."""
