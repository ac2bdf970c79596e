"""The application: a session (device, target, pool, world, schedule, renderer), the run loop
and its frame sources (offscreen, window), the CLI, the editor and the perf overlay."""
