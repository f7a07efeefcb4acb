"""Vulkan instance, validation layer and debug messenger; physical-device enumeration.

Validation messages of severity ERROR are collected; `Instance.check()` raises ValidationError
when any arrived, so tests (and `--validation`) fail loudly instead of printing and carrying on.
The binding supports only one module-global messenger callback, so messages are routed to the
live instances through a module-level registry.
"""

from __future__ import annotations

import atexit
import os
import weakref
from dataclasses import dataclass
from typing import Any

from vkpbr.errors import NoVulkanError, ValidationError
from vkpbr.gpu.vk import INSTALL_HINT, load, translate_errors

__all__ = ["Instance", "PhysicalDeviceInfo", "VALIDATION_LAYER"]

VALIDATION_LAYER = "VK_LAYER_KHRONOS_validation"
API_VERSION = (1, 3, 0)

_live: weakref.WeakSet[Instance] = weakref.WeakSet()

# Messages the validation layer prints that are not errors in our usage; kept empty unless a
# known layer bug forces an entry (with the VUID and a reason).
_IGNORED_MESSAGE_IDS: frozenset[str] = frozenset()


_anchor: Any = None


def _keep_drivers_loaded(vk: Any) -> None:
    """Hold one bare VkInstance for the life of the process (destroyed at exit), made when
    the last live instance is destroyed (not beside the first: a second vkCreateInstance on
    the way to the first frame).

    The loader unloads the driver (ICD) when the last instance goes away. NVIDIA's driver
    (580, measured on an H100) fails vkCreateInstance with VK_ERROR_INCOMPATIBLE_DRIVER after
    about 30 unload/reload cycles in one process, so a program that creates renderers in a
    loop would break. The anchor keeps the driver mapped; set VKPBR_KEEP_DRIVERS_LOADED=0 to
    opt out. Made through the raw binding, so `live_objects()` (gpu/vk.py) leaves it out.
    """
    global _anchor
    if _anchor is not None or os.environ.get("VKPBR_KEEP_DRIVERS_LOADED") == "0":
        return
    try:
        _anchor = vk.raw.vkCreateInstance(
            vk.VkInstanceCreateInfo(
                pApplicationInfo=vk.VkApplicationInfo(apiVersion=vk.VK_MAKE_VERSION(*API_VERSION))
            ),
            None,
        )
    except Exception:  # no driver: the real instance below reports it properly
        return
    atexit.register(_release_anchor)


def _release_anchor() -> None:
    global _anchor
    if _anchor is not None:
        handle, _anchor = _anchor, None
        load().raw.vkDestroyInstance(handle, None)


def _debug_callback(severity: int, types: int, data: Any, user_data: Any) -> int:
    vk = load()
    message = vk.ffi.string(data.pMessage).decode("utf-8", "replace")
    message_id = (
        vk.ffi.string(data.pMessageIdName).decode("utf-8", "replace")
        if data.pMessageIdName
        else ""
    )
    if message_id in _IGNORED_MESSAGE_IDS:
        return 0
    for inst in list(_live):
        inst._on_message(severity, message)
    return 0  # VK_FALSE: never abort the call


@dataclass(frozen=True)
class PhysicalDeviceInfo:
    """What `vkpbr info` prints about one device."""

    index: int
    name: str
    kind: str  # discrete, integrated, virtual, cpu, other
    api_version: str
    driver_version: int
    vendor_id: int
    device_id: int
    handle: Any


_KIND_RANK = {"discrete": 0, "integrated": 1, "virtual": 2, "cpu": 3, "other": 4}


class Instance:
    """A VkInstance with optional validation (and synchronization validation)."""

    def __init__(
        self,
        validation: bool = False,
        sync_validation: bool = False,
        extensions: tuple[str, ...] = (),
    ) -> None:
        """`extensions`: extra instance extensions that must be present (a window's surface
        extensions, for example); missing ones raise NoVulkanError."""
        vk = load()
        self.vk = vk
        self.validation = validation
        self.errors: list[str] = []
        self.warnings: list[str] = []
        self._messenger = None
        layers: list[str] = []
        enabled: list[str] = list(extensions)
        if enabled:
            available = {p.extensionName for p in vk.vkEnumerateInstanceExtensionProperties(None)}
            missing = [e for e in enabled if e not in available]
            if missing:
                raise NoVulkanError("vkCreateInstance", f"missing {', '.join(missing)}", INSTALL_HINT)
        if validation:
            available = {p.layerName for p in vk.vkEnumerateInstanceLayerProperties()}
            if VALIDATION_LAYER not in available:
                raise NoVulkanError(
                    "vkCreateInstance",
                    "validation layer missing",
                    "install vulkan-validationlayers (scripts/setup.sh does)",
                )
            layers.append(VALIDATION_LAYER)
            enabled.append(vk.VK_EXT_DEBUG_UTILS_EXTENSION_NAME)
        app = vk.VkApplicationInfo(
            pApplicationName="vkpbr",
            applicationVersion=vk.VK_MAKE_VERSION(0, 1, 0),
            pEngineName="vkpbr",
            engineVersion=vk.VK_MAKE_VERSION(0, 1, 0),
            apiVersion=vk.VK_MAKE_VERSION(*API_VERSION),
        )
        p_next = None
        if validation and sync_validation:
            self._features = vk.VkValidationFeaturesEXT(
                pEnabledValidationFeatures=[
                    vk.VK_VALIDATION_FEATURE_ENABLE_SYNCHRONIZATION_VALIDATION_EXT
                ],
            )
            p_next = self._features
        info = vk.VkInstanceCreateInfo(
            pNext=p_next,
            pApplicationInfo=app,
            ppEnabledLayerNames=layers,
            ppEnabledExtensionNames=enabled,
        )
        try:
            self.handle = vk.vkCreateInstance(info, None)
        except NoVulkanError:
            raise
        except Exception as exc:  # the loader found no driver at all
            raise NoVulkanError("vkCreateInstance", type(exc).__name__, INSTALL_HINT) from None
        _live.add(self)
        if validation:
            self._create_messenger()

    # --- validation -------------------------------------------------------------------------
    def _create_messenger(self) -> None:
        vk = self.vk
        create = vk.vkGetInstanceProcAddr(self.handle, "vkCreateDebugUtilsMessengerEXT")
        info = vk.VkDebugUtilsMessengerCreateInfoEXT(
            messageSeverity=vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_WARNING_BIT_EXT
            | vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT,
            messageType=vk.VK_DEBUG_UTILS_MESSAGE_TYPE_GENERAL_BIT_EXT
            | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_VALIDATION_BIT_EXT
            | vk.VK_DEBUG_UTILS_MESSAGE_TYPE_PERFORMANCE_BIT_EXT,
            pfnUserCallback=_debug_callback,
        )
        self._messenger = create(self.handle, info, None)

    def _on_message(self, severity: int, message: str) -> None:
        if severity & self.vk.VK_DEBUG_UTILS_MESSAGE_SEVERITY_ERROR_BIT_EXT:
            self.errors.append(message)
            if os.environ.get("VKPBR_PRINT_VALIDATION"):
                print("VALIDATION ERROR:", message)
        else:
            self.warnings.append(message)

    def check(self) -> None:
        """Raise ValidationError if the validation layer reported any error so far."""
        if self.errors:
            first = self.errors[0]
            raise ValidationError(
                f"{len(self.errors)} Vulkan validation error(s); first: {first}"
            )

    # --- devices ----------------------------------------------------------------------------
    def physical_devices(self) -> list[PhysicalDeviceInfo]:
        vk = self.vk
        kinds = {
            vk.VK_PHYSICAL_DEVICE_TYPE_DISCRETE_GPU: "discrete",
            vk.VK_PHYSICAL_DEVICE_TYPE_INTEGRATED_GPU: "integrated",
            vk.VK_PHYSICAL_DEVICE_TYPE_VIRTUAL_GPU: "virtual",
            vk.VK_PHYSICAL_DEVICE_TYPE_CPU: "cpu",
        }
        out = []
        with translate_errors("vkEnumeratePhysicalDevices"):
            handles = list(vk.vkEnumeratePhysicalDevices(self.handle))
        for i, h in enumerate(handles):
            p = vk.vkGetPhysicalDeviceProperties(h)
            v = p.apiVersion
            out.append(
                PhysicalDeviceInfo(
                    index=i,
                    name=p.deviceName,
                    kind=kinds.get(p.deviceType, "other"),
                    api_version=f"{v >> 22}.{(v >> 12) & 0x3FF}.{v & 0xFFF}",
                    driver_version=p.driverVersion,
                    vendor_id=p.vendorID,
                    device_id=p.deviceID,
                    handle=h,
                )
            )
        return out

    def choose_device(self, selector: str | int | None = None) -> PhysicalDeviceInfo:
        """Pick discrete > integrated > virtual > CPU, or the device named/indexed by selector."""
        from vkpbr.errors import UsageError

        devices = self.physical_devices()
        if not devices:
            raise NoVulkanError("vkEnumeratePhysicalDevices", "no devices", INSTALL_HINT)
        if selector is None or selector == "":
            return min(devices, key=lambda d: (_KIND_RANK[d.kind], d.index))
        text = str(selector)
        # (isdecimal: "²" is a digit int() refuses; past 18 digits no index exists, and
        # int() refuses past 4,300)
        if isinstance(selector, int) or text.isdecimal():
            idx = int(selector) if isinstance(selector, int) or len(text) <= 18 else -1
            if not 0 <= idx < len(devices):
                shown = text if len(text) <= 24 else f"{text[:10]}...{text[-10:]}"
                raise UsageError(
                    f"--device {shown}: no such device (have {len(devices)}; see `vkpbr info`)"
                )
            return devices[idx]
        matches = [d for d in devices if str(selector).lower() in d.name.lower()]
        if not matches:
            names = ", ".join(d.name for d in devices)
            raise UsageError(f"--device {selector!r}: no device matches (have: {names})")
        return matches[0]

    # --- lifetime ---------------------------------------------------------------------------
    def destroy(self) -> None:
        if getattr(self, "handle", None) is None:
            return
        vk = self.vk
        if self._messenger is not None:
            destroy = vk.vkGetInstanceProcAddr(self.handle, "vkDestroyDebugUtilsMessengerEXT")
            destroy(self.handle, self._messenger, None)
            self._messenger = None
        handle, self.handle = self.handle, None
        if not any(inst is not self and getattr(inst, "handle", None) is not None for inst in list(_live)):
            _keep_drivers_loaded(vk)  # before the last instance goes: the driver stays loaded
        vk.vkDestroyInstance(handle, None)
        _live.discard(self)
