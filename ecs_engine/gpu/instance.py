"""VkInstance with optional validation layers and a debug messenger that collects messages."""

from __future__ import annotations

from collections.abc import Iterable
from typing import Any

from ..errors import UsageError
from .functions import instance_function
from .loader import load_vulkan

VALIDATION_LAYER = "VK_LAYER_KHRONOS_validation"
API_VERSION = (1, 3, 0)  # dynamic rendering and synchronization2 (the frame graph) are core


class Instance:
    """Owns the VkInstance. With `validate`, every warning or error from the validation layers
    lands in `messages` (tests fail on any) and is also printed when `echo` is set."""

    def __init__(self, validate: bool = False, extensions: Iterable[str] = (), echo: bool = False) -> None:
        vk = self.vk = load_vulkan()
        self.validate = validate
        self.echo = echo
        self.messages: list[str] = []
        self._messenger = None
        self._handle = None
        layers: list[str] = []
        exts = list(extensions)
        available_exts = {e.extensionName for e in vk.vkEnumerateInstanceExtensionProperties(None)}
        missing = [e for e in exts if e not in available_exts]
        if missing:
            raise UsageError(f"the Vulkan loader lacks instance extension(s) {missing}")
        debug_info = None
        if validate:
            available = {layer.layerName for layer in vk.vkEnumerateInstanceLayerProperties()}
            if VALIDATION_LAYER not in available:
                raise UsageError(
                    "validation was requested but the Khronos validation layer is not installed: "
                    "sudo apt-get install -y vulkan-validationlayers"
                )
            layers.append(VALIDATION_LAYER)
            exts.append("VK_EXT_debug_utils")
            self._handle = vk.ffi.new_handle(self)
            debug_info = vk.VkDebugUtilsMessengerCreateInfoEXT(
                messageSeverity=vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT
                | vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
                messageType=vk.VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT
                | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT
                | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
                pfnUserCallback=_on_message,
                pUserData=self._handle,
            )
        app = vk.VkApplicationInfo(
            pApplicationName="ecs_engine",
            applicationVersion=1,
            pEngineName="ecs_engine",
            engineVersion=1,
            apiVersion=vk.VK_MAKE_VERSION(*API_VERSION),
        )
        info = vk.VkInstanceCreateInfo(
            pApplicationInfo=app,
            ppEnabledLayerNames=layers,
            ppEnabledExtensionNames=exts,
            pNext=debug_info,  # also covers vkCreateInstance/vkDestroyInstance themselves
        )
        try:
            self.handle = vk.vkCreateInstance(info, None)
        except vk.VkError as exc:
            raise UsageError(
                f"could not create a Vulkan instance ({type(exc).__name__}): is a Vulkan driver installed? "
                "sudo apt-get install -y mesa-vulkan-drivers"
            ) from exc
        if debug_info is not None:
            create = instance_function(self, "vkCreateDebugUtilsMessengerEXT")
            self._messenger = create(self.handle, debug_info, None)
        self._debug_info = debug_info  # keep the callback's owner alive

    def destroy(self) -> None:
        vk = self.vk
        if self._messenger is not None:
            instance_function(self, "vkDestroyDebugUtilsMessengerEXT")(self.handle, self._messenger, None)
            self._messenger = None
        if self.handle is not None:
            vk.vkDestroyInstance(self.handle, None)
            self.handle = None


def _on_message(severity: int, types: int, data: Any, user: Any) -> int:
    vk = load_vulkan()
    owner: Instance = vk.ffi.from_handle(user)
    text = data.pMessage if isinstance(data.pMessage, str) else vk.ffi.string(data.pMessage).decode(errors="replace")
    level = "error" if severity & vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT else "warning"
    owner.messages.append(f"[{level}] {text}")
    if owner.echo:
        print(f"vulkan validation {level}: {text}")
    return 0
