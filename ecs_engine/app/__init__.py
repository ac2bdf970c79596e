"""The application: a session (device, target, pool, world, schedule, renderer), the run loop, the window, the CLI, the editor and the perf overlay."""
