"""Runnable demo scenes (installed as ecs_engine.demos)."""
