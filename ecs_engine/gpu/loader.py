"""Importing the `vulkan` binding, which dlopens libvulkan.so.1 at import time."""

from __future__ import annotations

from types import ModuleType

from ..errors import UsageError

INSTALL_HINT = (
    "install it with `sudo apt-get install -y libvulkan1 mesa-vulkan-drivers vulkan-validationlayers` "
    "(or run `make demo`, which installs it)"
)


def load_vulkan() -> ModuleType:
    try:
        import vulkan
    except OSError as exc:  # the binding raises OSError when no loader library is found
        raise UsageError(f"no Vulkan loader (libvulkan.so.1) found: {INSTALL_HINT}") from exc
    except ImportError as exc:
        raise UsageError(f"the Python package `vulkan` is missing ({exc}); run `make demo` to install it") from exc
    return vulkan
