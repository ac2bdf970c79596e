"""GLSL sources and their committed SPIR-V (installed as ecs_engine.shaders)."""
