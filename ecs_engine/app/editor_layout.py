"""Layout helpers for the editor's narrow docked panels (300 pixels at 1280x720): fields that
leave room for their labels, and rows of buttons that wrap instead of running off the edge.

ImGui sizes a labelled field at 65% of the window and puts the label after it, and `same_line`
never wraps: in a 300-pixel panel a long label ("yaw pitch roll (deg)") or the fourth radio
button ("scale") was cut at the window's edge.
"""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

MIN_FIELD = 96.0  # pixels a field keeps however long its label: narrower, its value is unreadable


def push_label_room(imgui: Any, labels: Iterable[str]) -> None:
    """Make the fields that follow narrow enough for the widest of `labels` to show after them
    (undo with imgui.pop_item_width())."""
    room = max((imgui.calc_text_size(label).x for label in labels), default=0.0)
    room += imgui.get_style().item_inner_spacing.x
    imgui.push_item_width(max(imgui.get_content_region_avail().x - room, MIN_FIELD))


def button_width(imgui: Any, label: str) -> float:
    return float(imgui.calc_text_size(label).x + 2 * imgui.get_style().frame_padding.x)


def radio_width(imgui: Any, label: str) -> float:
    style = imgui.get_style()
    return float(imgui.get_frame_height() + style.item_inner_spacing.x + imgui.calc_text_size(label).x)


def same_line_if_fits(imgui: Any, width: float) -> None:
    """Put the next item (`width` pixels) after the last one if it fits before the window's
    right edge, else on a new line."""
    right = imgui.get_cursor_screen_pos().x + imgui.get_content_region_avail().x  # a new line's edge
    if imgui.get_item_rect_max().x + imgui.get_style().item_spacing.x + width <= right:
        imgui.same_line()


def hint(imgui: Any, text: str) -> None:
    """A tooltip for the last item: what a short label leaves out."""
    if imgui.is_item_hovered():
        imgui.set_tooltip(text)


def wrapped_colored(imgui: Any, color: tuple[float, float, float, float], text: str) -> None:
    """Coloured text wrapped at the window's edge (a status line can be a long error)."""
    imgui.push_text_wrap_pos(0.0)
    imgui.text_colored(color, text)
    imgui.pop_text_wrap_pos()
