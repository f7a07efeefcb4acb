"""Shared fixtures. Every renderer made in tests runs with the Khronos validation layer
(and synchronization validation unless VKPBR_SYNC_VALIDATION=0): a validation error raises
inside `Renderer.render`, and the factory below re-checks at teardown, so no error can pass.
"""

from __future__ import annotations

import os
from collections.abc import Callable, Iterator
from pathlib import Path

import numpy as np
import pytest
from assets_path import ASSETS
from hypothesis import Phase, settings

# Property tests shrink a failure before they report it. On the GPU machine each example
# makes a renderer, so shrinking can outlast the call: HYPOTHESIS_PROFILE=report (set by
# benchmarks/gpu_run.sh) reports the first failing example as found, unshrunk.
settings.register_profile("report", phases=(Phase.explicit, Phase.reuse, Phase.generate),
                          print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "default"))

# scripts/test.sh runs the suite on every core (pytest-xdist, up to 4 workers): a worker
# takes a whole module at a time, so a module's renderer fixtures are made once, as in one
# process; the folders whose tests share one machine-wide thing run in one worker, one
# module after another: tests/distributed (local Ray clusters), tests/viewer (X displays
# chosen by free number), tests/sample_viewer (Chromium and the Sample Viewer's server).
_ONE_WORKER = ("tests/distributed/", "tests/viewer/", "tests/sample_viewer/")


@pytest.hookimpl(optionalhook=True)
def pytest_xdist_make_scheduler(config: pytest.Config, log: object) -> object:
    from xdist.scheduler import LoadScopeScheduling

    class ModulesAndFolders(LoadScopeScheduling):
        def _split_scope(self, nodeid: str) -> str:
            path = nodeid.split("::", 1)[0]
            return next((f for f in _ONE_WORKER if path.startswith(f)), path)

    return ModulesAndFolders(config, log)


# Reproducible frame paths: on a GPU `--pipeline auto` measures the paths once a renderer has
# drawn for MEASURE_AFTER_S and may switch path mid-run (render/path_choice.py), so a module's
# renderer could change path between two renders a test compares (the H200's test pass on 8
# workers: 6 tests). The tests take the rule (CPUs: forward, as auto; GPUs: the compute path
# with the compute rasteriser); tests/gpu/test_path_choice.py sets auto for its own tests.
os.environ.setdefault("VKPBR_FRAME_PATHS", "rule")

# The sample models: $VKPBR_ASSETS, else .assets/models, else ../shared/assets (assets_path.py).
# Tests that need them take the `assets` fixture, which skips with the folder's name when absent.


@pytest.fixture(scope="session")
def assets() -> Path:
    if not ASSETS.is_dir():
        pytest.skip(f"sample assets not found at {ASSETS} (set VKPBR_ASSETS)")
    return ASSETS


@pytest.fixture
def sample_scene(assets: Path) -> Callable[[str], object]:
    """Loads sample model NAME (NAME/glTF/NAME.gltf of the assets), skipping when it is not
    in this copy of the assets."""

    def load(name: str) -> object:
        from vkpbr.scene.loader import load_scene

        path = assets / name / "glTF" / f"{name}.gltf"
        if not path.is_file():
            pytest.skip(f"{path} not in the assets")
        return load_scene(path)

    return load


@pytest.fixture
def rng() -> np.random.Generator:
    return np.random.default_rng(1234)


@pytest.fixture
def make_renderer() -> Iterator[Callable[..., object]]:
    """Factory for validated renderers; closes them and checks validation at teardown."""
    from vkpbr.render.renderer import Renderer

    made: list[Renderer] = []

    def factory(scene=None, wait_ahead=True, **kwargs):  # noqa: ANN001, ANN202
        kwargs.setdefault("validation", True)
        kwargs.setdefault("sync_validation", os.environ.get("VKPBR_SYNC_VALIDATION", "1") != "0")
        r = Renderer(scene, **kwargs)
        made.append(r)
        if wait_ahead:  # the kernels a GPU compiles ahead (render/kernels_ahead.py) done, so
            r.device.wait_background()  # that tests counting a frame's builds count its own
        return r

    yield factory
    for r in made:
        instance = r.device.instance
        r.close()
        assert instance.errors == [], instance.errors[:3]
