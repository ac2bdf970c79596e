"""ecs_engine.maths."""
