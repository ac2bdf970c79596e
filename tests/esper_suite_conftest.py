"""Copied as conftest.py beside esper's own tests by test_esper_suite.py, so that ``import esper``
there gives ecs_engine.esper_compat. (Without the test_ prefix pytest does not collect it here.)"""

import sys

import pytest

import ecs_engine.esper_compat as adapter

sys.modules["esper"] = adapter


def pytest_collection_modifyitems(items: list[pytest.Item]) -> None:
    """Refuse to run if a test module still got the real esper: its results would prove nothing."""
    for item in items:
        module = getattr(item, "module", None)
        if module is not None and getattr(module, "esper", adapter) is not adapter:
            raise pytest.UsageError(f"{module.__name__} imported the real esper, not the adapter")
