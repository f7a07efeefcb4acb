"""vkpbr's exception hierarchy: every error a user can cause derives from VkpbrError.

The CLI turns a VkpbrError into one line on stderr and a non-zero exit; anything else is a bug.
"""

from __future__ import annotations

__all__ = [
    "VkpbrError",
    "UsageError",
    "SceneError",
    "BakeFormatError",
    "JsonError",
    "OutputError",
    "VulkanError",
    "NoVulkanError",
    "OutOfDeviceMemoryError",
    "DeviceLostError",
    "ValidationError",
    "ShaderError",
]


class VkpbrError(Exception):
    """Base class of every error vkpbr raises on purpose."""

    def __str__(self) -> str:
        # A path from a job file or an API call may hold a NUL byte: shown as \0, so that
        # a message stays text a terminal and a log can take.
        return super().__str__().replace("\0", "\\0")


class UsageError(VkpbrError, ValueError):
    """A bad option value: unknown view name, image size of 0, malformed camera, ..."""


class SceneError(VkpbrError):
    """A scene file that cannot be loaded. The message names the file and the problem."""

    def __init__(self, path: object, problem: str) -> None:
        self.path = str(path)
        self.problem = problem
        super().__init__(f"{self.path}: {problem}")


class BakeFormatError(SceneError):
    """A baked file that is truncated, corrupt, of another version or stale."""


class VulkanError(VkpbrError):
    """A Vulkan call failed; carries the VkResult name and the function."""

    def __init__(self, function: str, result: str, hint: str = "") -> None:
        self.function = function
        self.result = result
        message = f"{function} failed with {result}"
        super().__init__(f"{message}: {hint}" if hint else message)


class NoVulkanError(VulkanError):
    """No Vulkan loader or no driver: tells the user what to install."""


class OutOfDeviceMemoryError(VulkanError, MemoryError):
    """The GPU (or lavapipe's heap) ran out of memory."""


class DeviceLostError(VulkanError):
    """The device was lost (driver crash, GPU reset)."""


class GpuTimeoutError(VulkanError):
    """The GPU did not finish a submission in time: a hung device (or a frame far larger than
    $VKPBR_GPU_TIMEOUT_S allows)."""


class ValidationError(VkpbrError):
    """The Khronos validation layer reported one or more errors."""


class ShaderError(VkpbrError):
    """A SPIR-V module is missing or stale, or glslc failed."""


class JsonError(VkpbrError, ValueError):
    """A JSON input that is malformed or over vkpbr's limits (vkpbr/json_input.py). The
    message names the file (or what the JSON came from) and the problem; readers of one kind
    of file usually re-raise it as their own error (UsageError, SceneError) with `problem`."""

    def __init__(self, where: object, problem: str) -> None:
        self.where = str(where)
        self.problem = problem
        super().__init__(f"{self.where}: {problem}")


def shown_path(path: object) -> str:
    """`path` as messages show it: whole when short, else its start and end around "..."
    (a 5,000-character path would bury the problem), NUL bytes written as \\0."""
    text = str(path).replace("\0", "\\0")
    if len(text) <= 120:
        return text
    return f"{text[:60]}...{text[-50:]} ({len(text):,} characters)"


class OutputError(VkpbrError, OSError):
    """A file vkpbr writes (an image, a baked file, a camera file, a manifest) could not be
    written: one line naming the file and the reason. An OSError too (`errno`, `filename`),
    so code that caught the OSError of a failed write still catches it."""

    def __init__(self, path: object, problem: str, code: int | None = None) -> None:
        OSError.__init__(self, code, problem, str(path))
        self.path = str(path)
        self.problem = problem

    def __str__(self) -> str:
        return f"{shown_path(self.path)}: cannot write: {self.problem}"
