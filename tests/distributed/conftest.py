"""The local Ray cluster the Ray tests share (test_ray_job.py, test_ray_worlds.py): started
once a session, since each start costs seconds on a small machine."""

from __future__ import annotations

import os

import pytest


@pytest.fixture(scope="session")
def cluster(tmp_path_factory: pytest.TempPathFactory):  # noqa: ANN201
    """One Ray instance (2 CPU workers); the actors inherit the validation layer and a bake
    cache of the tests' own."""
    ray = pytest.importorskip("ray", reason="the ray extra is not installed (pip install "
                              "'vkpbr[ray]')", exc_type=ImportError)
    saved = {k: os.environ.get(k) for k in ("VKPBR_VALIDATION", "VKPBR_CACHE_DIR")}
    cache = tmp_path_factory.mktemp("cache")
    os.environ.update(VKPBR_VALIDATION="1", VKPBR_CACHE_DIR=str(cache))
    if ray.is_initialized():
        ray.shutdown()
    ray.init(num_cpus=2, include_dashboard=False, log_to_driver=False, logging_level="WARNING")
    yield {"address": ray.get_runtime_context().gcs_address, "cache": cache}
    ray.shutdown()
    for k, v in saved.items():
        if v is None:
            os.environ.pop(k, None)
        else:
            os.environ[k] = v
