"""The device report `vkpbr info` prints, for the app layer (which does not reach into gpu/)."""

from __future__ import annotations

from vkpbr.gpu.info import device_report

__all__ = ["device_report"]
