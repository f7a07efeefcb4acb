"""The environments a renderer's frames sample, and the one bound in its frame slots.

`EnvironmentStore` pre-filters an environment (render/environment.py EnvironmentBaker: the
built-in sky, a panorama file's, or a black one where none lights the frame) on the first
frame that asks for it and keeps it, by source, while it is among the ENVIRONMENTS_KEPT most
recently used: it depends on no
scene, so a Renderer's scenes (render/scene_swap.py) share one store, made once, whose
images are the device's (`Device.keeping`), not a scene's. `Environments` is one scene's
view of it: the one bound in its frame slots. Binding another one into the slots' set 2 is
rare (a new environment, or a new scene's slots): the sets may be in use by queued frames and
named by recorded command buffers, so it waits for the device and drops the recordings.
"""

from __future__ import annotations

import contextlib
import os
from pathlib import Path

from vkpbr.gpu.descriptors import DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.render.environment import Environment, EnvironmentBaker, EnvironmentSpec
from vkpbr.render.frames import FrameSlot
from vkpbr.render.options import RenderOptions
from vkpbr.render.recorder import FrameRecorder
from vkpbr.scene.environment import load_panorama
from vkpbr.shading import SUN_DIRECTION

__all__ = ["EnvironmentStore", "Environments", "env_key", "ENVIRONMENTS_KEPT"]

# Pre-filtered environments kept, the least recently bound destroyed past it: a dataset that
# lights every image with another panorama had kept each (a 4096x2048 one's radiance cube
# and pre-filtered chain: ~70 MiB of device memory) for the device's life.
ENVIRONMENTS_KEPT = 4


class EnvironmentStore:
    """The pre-filtered environments of one device, by source (see the module's docstring).
    `spec`: the pre-filter's sizes (None: the GPU sizes, EnvironmentSpec.cpu() on a CPU
    device); `cache_dir`: where the split-sum BRDF table is kept between processes (None:
    made once per process)."""

    def __init__(self, device: Device, spec: EnvironmentSpec | None = None,
                 cache_dir: str | os.PathLike[str] | None = None) -> None:
        self.device, self._spec, self._cache_dir = device, spec, cache_dir
        self._baker: EnvironmentBaker | None = None
        self._made: dict[tuple, Environment] = {}  # by env_key (a file's: its size, time)

    @property
    def baker(self) -> EnvironmentBaker:
        """The environment compute pipelines (made on first use)."""
        if self._baker is None:
            spec = self._spec
            if spec is None:
                spec = EnvironmentSpec.cpu() if self.device.info.kind == "cpu" else EnvironmentSpec()
            cache = Path(self._cache_dir) if self._cache_dir is not None else None
            with self.device.keeping():
                self._baker = EnvironmentBaker(self.device, spec, cache)
        return self._baker

    def get(self, options: RenderOptions) -> Environment:
        """The environment frames with `options` sample (pre-filtered on first use, then
        kept): the sky, a panorama file's, or a black one where none lights the frame.

        Raises SceneError (one line naming the file) for an unreadable panorama."""
        key = env_key(options)
        if key[0] == "file":  # (a file written again under its name is another panorama)
            with contextlib.suppress(OSError):  # (a missing one: load_panorama's error)
                st = os.stat(key[1])
                key = (*key, st.st_size, st.st_mtime_ns)
        env = self._made.pop(key, None)
        if env is not None:
            self._made[key] = env  # (the most recently used last)
        else:
            baker = self.baker
            pixels = load_panorama(key[1]) if key[0] == "file" else None  # (before any bake)
            with self.device.keeping():  # (the bake's own temporaries it destroys itself)
                if key[0] == "black":
                    env = baker.from_constant((0.0, 0.0, 0.0))
                elif key[0] == "sky":
                    env = baker.from_sky(SUN_DIRECTION)
                else:
                    env = baker.from_panorama(pixels, key[1])
            self._made[key] = env
        return env

    def trim(self, bound: Environment) -> None:
        """Destroy the least recently used environments past ENVIRONMENTS_KEPT, never
        `bound` (the one the frame slots sample). The caller has the device idle and the
        recordings that sampled the others dropped (Environments._bind)."""
        for key in list(self._made):
            if len(self._made) <= ENVIRONMENTS_KEPT:
                return
            if self._made[key] is not bound:
                self._made.pop(key).destroy()

    def destroy(self) -> None:
        for env in self._made.values():
            env.destroy()
        self._made = {}
        if self._baker is not None:
            self._baker.destroy()
            self._baker = None


class Environments:
    """The environment bound in the frame slots `slots` (drawn with `recorder`), from
    `store` (the device's, shared with the Renderer's other scenes)."""

    def __init__(self, device: Device, slots: list[FrameSlot], recorder: FrameRecorder,
                 store: EnvironmentStore) -> None:
        self.device, self.slots, self.recorder, self.store = device, slots, recorder, store
        self._bound: Environment | None = None  # what every slot's set 2 samples

    def get(self, options: RenderOptions) -> Environment:
        """The environment frames with `options` sample (EnvironmentStore.get)."""
        return self.store.get(options)

    def bind_for(self, options: RenderOptions) -> None:
        """Make every frame slot sample the environment `options` ask for."""
        env = self.get(options)
        if env is not self._bound:
            self._bind(env)

    def _bind(self, env: Environment) -> None:
        """Point every slot's set 2 samplers at `env`, with the device idle and the recorded
        command buffers dropped (an updated set invalidates them)."""
        self.device.wait_idle()
        self.recorder.free()
        writer = DescriptorWriter(self.device)
        for slot in self.slots:
            for binding, image in ((2, env.specular), (3, env.irradiance), (4, env.brdf_lut)):
                writer.sampler(slot.set2, binding, image.view, image.sampler)
        writer.update()
        self._bound = env
        self.store.trim(env)


def env_key(options: RenderOptions) -> tuple:
    """Which environment `options` sample: ("black",), ("sky",) or ("file", absolute path)."""
    if not options.has_environment:
        return ("black",)
    if options.env == "sky":
        return ("sky",)
    return ("file", os.path.abspath(options.env))
