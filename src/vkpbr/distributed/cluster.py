"""The Ray side of the driver: connecting to a cluster (or starting a local one), and the
renderer actors' resources. Ray is imported only here and in the driver's loop."""

from __future__ import annotations

import logging
import socket
from typing import Any

from vkpbr.distributed.actor import RendererActor
from vkpbr.errors import UsageError, VkpbrError

__all__ = ["ClusterError", "import_ray", "preflight", "connect", "actor_plan", "RayRenderer",
           "RAY_INSTALL"]

RAY_INSTALL = "pip install 'vkpbr[ray]'"
CONNECT_TIMEOUT_S = 5.0


class ClusterError(VkpbrError):
    """The Ray cluster cannot be reached, or has no room for a renderer actor."""


def import_ray() -> Any:
    """The ray module, or a one-line UsageError with the install command."""
    try:
        import ray
    except ImportError as exc:
        raise UsageError(f"rendering on Ray needs the ray extra ({exc}): {RAY_INSTALL}") from None
    return ray


def preflight(address: str) -> None:
    """Fail in seconds, in one line, where nothing listens at `address` (ray.init would
    retry for a minute and then print a page)."""
    if address == "auto":
        return
    hostport = address.removeprefix("ray://")
    host, _, port = hostport.rpartition(":")
    if not host or not port.isdigit():
        raise UsageError(f"Ray address {address!r}: expected HOST:PORT, ray://HOST:PORT or auto")
    try:
        socket.create_connection((host.strip("[]"), int(port)), timeout=CONNECT_TIMEOUT_S).close()
    except OSError as exc:
        raise ClusterError(f"Ray cluster at {address}: cannot connect ({exc.strerror or exc}); "
                           "start one with `ray start --head`, or check the address") from None


def connect(ray: Any, address: str | None, num_cpus: int | None) -> bool:
    """Connect to the cluster at `address` (None: start a local one); True when this call
    started Ray (and so shuts it down at the end). An initialised Ray is used as it is."""
    if address not in (None, "local"):
        preflight(address)
    if ray.is_initialized():
        return False
    kwargs: dict[str, Any] = {"logging_level": logging.WARNING, "log_to_driver": False}
    try:
        if address in (None, "local"):
            ray.init(num_cpus=num_cpus, include_dashboard=False, **kwargs)
        else:
            ray.init(address=address, **kwargs)
    except Exception as exc:  # noqa: BLE001 - Ray's own exceptions vary by version
        text = str(exc).strip().splitlines()
        raise ClusterError(f"Ray cluster at {address or 'local'}: cannot start or join "
                           f"({text[0] if text else type(exc).__name__})") from None
    return True


class RayRenderer(RendererActor):
    """The actor Ray runs: the Vulkan device of the GPU Ray gave it (None on CPU workers).
    Vulkan lists devices in the order CUDA does on a node of one GPU model; mixed nodes
    should name the device in the job instead."""

    def __init__(self) -> None:
        import ray

        ids = [str(i) for i in ray.get_gpu_ids()]
        # A GPU id that is not an index (a UUID in CUDA_VISIBLE_DEVICES): the default device.
        super().__init__(int(ids[0]) if ids and ids[0].isdigit() else None)


def actor_plan(ray: Any, actors: int | None, num_cpus: float | None,
                num_gpus: float | None) -> tuple[int, dict[str, float]]:
    """How many actors and the resources of each: one per GPU, else one per CPU."""
    res = ray.cluster_resources()
    gpus, cpus = float(res.get("GPU", 0)), float(res.get("CPU", 0))
    if num_gpus is None and num_cpus is None:
        if gpus >= 1:
            num_gpus, num_cpus = 1.0, 1.0
        else:
            num_gpus, num_cpus = 0.0, 1.0
    num_gpus, num_cpus = float(num_gpus or 0), float(num_cpus if num_cpus is not None else 1)
    if num_gpus > gpus:
        raise ClusterError(f"the Ray cluster has {gpus:g} GPUs; a renderer actor asks for {num_gpus:g}")
    if num_cpus > cpus:
        raise ClusterError(f"the Ray cluster has {cpus:g} CPUs; a renderer actor asks for {num_cpus:g}")
    if actors is None:
        fit = [gpus / num_gpus] if num_gpus else []
        fit.append(cpus / num_cpus if num_cpus else cpus)
        actors = max(1, int(min(fit) + 1e-9))
    if actors < 1:
        raise UsageError(f"actors: expected at least 1, got {actors}")
    return actors, {"num_cpus": num_cpus, "num_gpus": num_gpus}
