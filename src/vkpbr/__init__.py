"""vkpbr: physically based real-time rendering in Python on Vulkan."""

from __future__ import annotations

__version__ = "0.1.0"
