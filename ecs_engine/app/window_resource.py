"""`Window`: the run's window as a world resource a game reads and changes while it runs.

    window = world.resources[Window]
    window.title = f"Catch - {score.points} points"
    window.cursor_captured = True          # mouse-look: the pointer hidden, its moves unbounded
    window.fullscreen = True
    window.size = (1280, 720)
    window.close()                         # end the run after this frame, as Esc does

A change goes to GLFW at once (no system polls it every frame). A headless or simulation run
has the resource too, with nothing to show it: the values are kept and `close()` still ends
the run.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Any

MAX_SIZE = 16384  # pixels a side, as the CLI's --width / --height


class Window:
    def __init__(
        self, title: str, size: tuple[int, int], fullscreen: bool = False, cursor_captured: bool = False
    ) -> None:
        self._title = str(title)
        self._size = check_size(size)
        self._fullscreen = bool(fullscreen)
        self._cursor_captured = bool(cursor_captured)
        self._glfw: Any = None
        self._handle: Any = None
        self._close: Callable[[], None] | None = None
        self._windowed_at: tuple[int, int, int, int] | None = None  # x, y, width, height before fullscreen

    def bind(self, glfw: Any, handle: Any, close: Callable[[], None]) -> None:
        """The run opened: `glfw` and `handle` are its window (None headless), `close` ends it."""
        self._glfw, self._handle, self._close = glfw, handle, close
        if handle is not None:
            glfw.set_window_title(handle, self._title)
            if self._fullscreen:
                self._set_fullscreen(True)
            if self._cursor_captured:
                self._set_cursor(True)

    def unbind(self) -> None:
        self._glfw = self._handle = self._close = None

    @property
    def shown(self) -> bool:
        """Whether there is a window on screen (False headless and in a simulation)."""
        return self._handle is not None

    @property
    def title(self) -> str:
        return self._title

    @title.setter
    def title(self, value: str) -> None:
        self._title = str(value)
        if self._handle is not None:
            self._glfw.set_window_title(self._handle, self._title)

    @property
    def size(self) -> tuple[int, int]:
        """Width and height in screen units (what the user resized it to, in a window)."""
        if self._handle is not None:
            width, height = self._glfw.get_window_size(self._handle)
            return int(width), int(height)
        return self._size

    @size.setter
    def size(self, value: tuple[int, int]) -> None:
        self._size = check_size(value)
        if self._handle is not None and not self._fullscreen:
            self._glfw.set_window_size(self._handle, *self._size)

    @property
    def fullscreen(self) -> bool:
        return self._fullscreen

    @fullscreen.setter
    def fullscreen(self, value: bool) -> None:
        value = bool(value)
        if value != self._fullscreen and self._handle is not None:
            self._set_fullscreen(value)
        self._fullscreen = value

    @property
    def cursor_captured(self) -> bool:
        """Mouse-look: the pointer hidden and held by the window, its moves (InputState's mouse)
        unbounded; False gives it back."""
        return self._cursor_captured

    @cursor_captured.setter
    def cursor_captured(self, value: bool) -> None:
        self._cursor_captured = bool(value)
        if self._handle is not None:
            self._set_cursor(self._cursor_captured)

    def close(self) -> None:
        """End the run after this frame (what Esc and the window's close button do)."""
        if self._close is not None:
            self._close()

    def _set_fullscreen(self, on: bool) -> None:
        glfw, handle = self._glfw, self._handle
        if on:
            monitor = glfw.get_primary_monitor()
            mode = glfw.get_video_mode(monitor) if monitor else None
            if mode is None:
                return  # no monitor to fill (some virtual displays): the window stays as it is
            x, y = glfw.get_window_pos(handle)
            self._windowed_at = (x, y, *self.size)
            glfw.set_window_monitor(handle, monitor, 0, 0, mode.size.width, mode.size.height, mode.refresh_rate)
        else:
            x, y, width, height = self._windowed_at or (64, 64, *self._size)
            glfw.set_window_monitor(handle, None, x, y, width, height, 0)

    def _set_cursor(self, captured: bool) -> None:
        glfw, handle = self._glfw, self._handle
        glfw.set_input_mode(handle, glfw.CURSOR, glfw.CURSOR_DISABLED if captured else glfw.CURSOR_NORMAL)
        if glfw.raw_mouse_motion_supported():
            glfw.set_input_mode(handle, glfw.RAW_MOUSE_MOTION, glfw.TRUE if captured else glfw.FALSE)


def check_size(size: Any) -> tuple[int, int]:
    try:
        width, height = (int(v) for v in size)
        ok = all(float(v) == int(v) for v in size)
    except (TypeError, ValueError):
        ok = False
    if not ok or not (0 < width <= MAX_SIZE and 0 < height <= MAX_SIZE):
        raise ValueError(f"a window size is (width, height), whole numbers from 1 to {MAX_SIZE}, not {size!r:.80}")
    return width, height
