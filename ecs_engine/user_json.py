"""JSON from files a user opens (a scene's header, a bindings file, a glTF): parsed with bounds, so
a hostile file gets one ValueError saying what is wrong instead of a RecursionError, an
OverflowError or a number no later check expects.

- nesting: at most MAX_DEPTH arrays and objects deep (Python's parser recurses, and so does
  any code walking the result);
- integers: at most MAX_INT_DIGITS digits (every integer the engine reads fits in 64 bits);
- no NaN, Infinity, or floats that overflow to them (1e999).
"""

from __future__ import annotations

import json
from typing import Any, Final

__all__ = ["MAX_DEPTH", "MAX_INT_DIGITS", "UserJsonError", "parse_json"]

MAX_DEPTH: Final = 64
MAX_INT_DIGITS: Final = 20


class UserJsonError(ValueError):
    """JSON that is not read (the message says why and where)."""


def _int(text: str) -> int:
    digits = len(text.lstrip("-"))
    if digits > MAX_INT_DIGITS:
        raise UserJsonError(f"an integer of {digits} digits (at most {MAX_INT_DIGITS} are read)")
    return int(text)


def _float(text: str) -> float:
    value = float(text)
    if value in (float("inf"), float("-inf")):
        raise UserJsonError(f"the number {text[:40]} is too large for a float")
    return value


def _constant(name: str) -> float:
    raise UserJsonError(f"{name} is not a number JSON allows")


def _depth(value: Any) -> int:
    """The deepest nesting of arrays and objects in a parsed value, walked without recursion."""
    deepest, todo = 0, [(value, 1)]
    while todo:
        item, depth = todo.pop()
        children = item.values() if isinstance(item, dict) else item if isinstance(item, list) else None
        if children is not None:
            deepest = max(deepest, depth)
            todo.extend((child, depth + 1) for child in children if isinstance(child, (dict, list)))
    return deepest


def parse_json(text: str | bytes) -> Any:
    """The value in `text` (bytes: UTF-8, as RFC 8259 asks), or UserJsonError (a ValueError)
    saying what is wrong."""
    if isinstance(text, bytes):
        try:
            text = text.decode("utf-8")
        except UnicodeDecodeError as exc:
            raise UserJsonError(f"not UTF-8 text ({exc})") from None
    try:
        value = json.loads(text, parse_int=_int, parse_float=_float, parse_constant=_constant)
    except UserJsonError:
        raise
    except RecursionError:  # the parser recurses once per level
        raise UserJsonError(f"nested too deeply; at most {MAX_DEPTH} levels of arrays and objects are read") from None
    except ValueError as exc:  # json.JSONDecodeError is one
        raise UserJsonError(f"not JSON ({exc})") from None
    depth = _depth(value)
    if depth > MAX_DEPTH:
        raise UserJsonError(f"nested {depth} deep; at most {MAX_DEPTH} levels of arrays and objects are read")
    return value
