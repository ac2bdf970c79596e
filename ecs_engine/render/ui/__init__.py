"""Dear ImGui drawn by the engine: its pass, its texture uploads and engine images shown in it."""
