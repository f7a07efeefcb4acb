"""The environment's GPU objects: a radiance cube from a panorama or the built-in sky, and its
pre-filtered forms for image-based lighting, all made in compute shaders.

    baker = EnvironmentBaker(device)           # compute pipelines, made once per device
    env = baker.from_panorama(load_panorama("studio.hdr"))   # or baker.from_sky(SUN_DIRECTION)
    writer.sampler(set2, 2, env.specular.view, env.specular.sampler)   # samplerCube
    writer.sampler(set2, 3, env.irradiance.view, env.irradiance.sampler)
    writer.sampler(set2, 4, env.brdf_lut.view, env.brdf_lut.sampler)
    lighting.env_rotation = (cos, sin, env.max_lod, 0)

Steps (shaders/env_*.comp): the panorama (RGBA16F, bilinear) or the sky is drawn into the
source cube's level 0, whose mip chain is blitted; the specular cube's level k is the source
pre-filtered with GGX of roughness k / max_lod by importance sampling (mip-filtered samples:
no fireflies); the irradiance cube is the cosine convolution; the split-sum BRDF table is made
once, read back and kept on disk (`cache_dir`, the bake cache: brdf_lut-v1-128x128-512.npy),
so later processes upload it. Pre-filtered environments are not cached on disk: on a GPU the
pre-filter of a 2k x 1k panorama costs milliseconds, less than reading its result back.
"""

from __future__ import annotations

import contextlib
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from vkpbr.atomic import atomic_writer
from vkpbr.gpu.commands import Commands
from vkpbr.gpu.compute import ComputePipeline, groups, make_at_once
from vkpbr.gpu.descriptors import BindingSpec, DescriptorPool, DescriptorSetLayout, DescriptorWriter
from vkpbr.gpu.device import Device
from vkpbr.gpu.image import Image, ImageView, Sampler, SamplerSpec
from vkpbr.gpu.image_io import read_rgba16f, rgba16f_format, upload_rgba16f
from vkpbr.render.codegen import SPV_DIR
from vkpbr.scene.environment import check_panorama
from vkpbr.scene.sky import TURBIDITY, sky_model
from vkpbr.shading import SUN_DIRECTION

__all__ = ["EnvironmentSpec", "SampledImage", "Environment", "EnvironmentBaker", "LUT_SIZE",
           "LUT_SAMPLES"]

log = logging.getLogger(__name__)

LUT_SIZE = 128
LUT_SAMPLES = 512
LUT_VERSION = 1
_LUT_MEMORY: dict[tuple[int, int], np.ndarray] = {}  # one table per process


@dataclass(frozen=True)
class EnvironmentSpec:
    """Sizes and sample counts (GPU-sized defaults; `small()` for lavapipe tests).

    source_size : texels per face of the radiance cube (None: from the panorama, W / 4 as a
        power of two in [16, 1024]; 256 for the sky).
    specular_size : level 0 of the pre-filtered cube (at most the source's); its chain ends
        at 4 x 4, so max_lod = log2(specular_size) - 2.
    """

    source_size: int | None = None
    specular_size: int = 256
    specular_samples: int = 128
    irradiance_size: int = 32
    irradiance_samples: int = 256
    sky_size: int = 256

    @staticmethod
    def small() -> EnvironmentSpec:
        return EnvironmentSpec(source_size=None, specular_size=32, specular_samples=64,
                               irradiance_size=8, irradiance_samples=128, sky_size=32)

    @staticmethod
    def cpu() -> EnvironmentSpec:
        """The renderer's sizes on a CPU device (lavapipe): a 128^2 sky and pre-filter, which
        bake in well under a second there (the GPU sizes take seconds)."""
        return EnvironmentSpec(source_size=None, specular_size=128, specular_samples=32,
                               irradiance_size=16, irradiance_samples=128, sky_size=128)


@dataclass
class SampledImage:
    """What a combined-image-sampler binding takes: the image, its view and a sampler."""

    image: Image
    view: ImageView
    sampler: Sampler


@dataclass
class Environment:
    """A pre-filtered environment (owned objects; `destroy()` frees them, the device's
    close() does too).

    specular : cube view over the GGX mip chain (roughness = lod / max_lod).
    irradiance : small cube, cosine-weighted mean radiance.
    brdf_lut : 2D, RG = (A, B) of the split sum, x = n.v, y = roughness.
    source : the radiance cube itself (with mips): the background reads `specular` lod 0.
    max_lod : mip count - 1 of `specular` (Lighting.env_rotation.z).
    bake_ms : wall time of the pre-filter (upload excluded), for the log and benchmarks.
    """

    specular: SampledImage
    irradiance: SampledImage
    brdf_lut: SampledImage
    source: SampledImage
    max_lod: int
    bake_ms: float
    _owned: tuple[Any, ...] = ()

    def destroy(self) -> None:
        for obj in reversed(self._owned):
            obj.destroy()
        self._owned = ()


def _pow2_at_least(x: float) -> int:
    return 1 << max(int(np.ceil(np.log2(max(x, 1.0)))), 0)


class EnvironmentBaker:
    """The environment compute pipelines of one device (kept for the device's life)."""

    def __init__(self, device: Device, spec: EnvironmentSpec = EnvironmentSpec(),
                 cache_dir: Path | None = None) -> None:
        self.device = device
        self.spec = spec
        self.cache_dir = cache_dir
        stages = ("compute",)
        self.layout = DescriptorSetLayout(device, [BindingSpec(0, "samplerCube", stages, "src"),
                                                   BindingSpec(1, "storage_image", stages, "dst")])
        self.layout_no_src = DescriptorSetLayout(
            device, [BindingSpec(1, "storage_image", stages, "dst")])
        self.layout_2d = DescriptorSetLayout(device, [BindingSpec(0, "sampler2D", stages, "src"),
                                                      BindingSpec(1, "storage_image", stages,
                                                                  "dst")])
        keep = device.keeps_here()  # (the makers' threads keep what this one keeps)

        def pipe(name: str, layout: DescriptorSetLayout, push: int) -> Callable[[], ComputePipeline]:
            def make() -> ComputePipeline:
                with device.keeping() if keep else contextlib.nullcontext():
                    return ComputePipeline(device, SPV_DIR / f"{name}.comp.spv", [layout], push)
            return make
        self.equirect, self.sky, self.specular, self.irradiance, self.lut = make_at_once([
            pipe("env_equirect", self.layout_2d, 16), pipe("env_sky", self.layout_no_src, 128),
            pipe("env_specular", self.layout, 16), pipe("env_irradiance", self.layout, 16),
            pipe("env_brdf_lut", self.layout_no_src, 16)])
        self.cube_sampler = Sampler(device, SamplerSpec("clamp", "clamp", anisotropy=1.0))
        self.lut_sampler = Sampler(device, SamplerSpec("clamp", "clamp", mipmaps=False,
                                                       anisotropy=1.0))
        self._lut: SampledImage | None = None

    def destroy(self) -> None:
        if self._lut is not None:
            self._lut.view.destroy()
            self._lut.image.destroy()
            self._lut = None
        for obj in (self.lut_sampler, self.cube_sampler, self.lut, self.irradiance,
                    self.specular, self.sky, self.equirect, self.layout_2d, self.layout_no_src,
                    self.layout):
            obj.destroy()

    # --- entry points -----------------------------------------------------------------------
    def from_panorama(self, pixels: np.ndarray, source: object = "<array>", *,
                      size: int | None = None,
                      irradiance_size: int | None = None) -> Environment:
        """Pre-filter an (H, W, 3) equirectangular panorama (checked by check_panorama);
        `size`, `irradiance_size` override the spec's cube sizes."""
        rgb = check_panorama(pixels, source)
        h, w = rgb.shape[:2]
        size = size or self.spec.source_size or int(np.clip(_pow2_at_least(w / 4), 16, 1024))
        vk = self.device.vk
        pano = upload_rgba16f(self.device, rgb, name="panorama")
        pano_view = ImageView(pano)
        pano_sampler = Sampler(self.device, SamplerSpec("repeat", "clamp", mipmaps=False,
                                                        anisotropy=1.0))
        try:
            def draw(cmd: Commands, pool: DescriptorPool, dst: ImageView) -> None:
                ds = pool.allocate(self.layout_2d)
                wr = DescriptorWriter(self.device)
                wr.sampler(ds, 0, pano_view, pano_sampler)
                wr.storage_image(ds, 1, dst)
                wr.update()
                cmd.bind_pipeline(self.equirect)
                cmd.bind_set(0, ds)
                cmd.push(np.array([size, 0, 0, 0], np.uint32))
                cmd.dispatch(*groups((size, size, 6), (8, 8, 1)))
            return self._bake(size, draw, irradiance_size)
        finally:
            pano_sampler.destroy()
            pano_view.destroy()
            pano.destroy()
            del vk

    def from_sky(self, sun_direction: tuple[float, float, float] = SUN_DIRECTION,
                 turbidity: float = TURBIDITY) -> Environment:
        """The built-in Preetham sky (scene/sky.py) for a sun whose light travels along
        `sun_direction`, made on the GPU."""
        size = self.spec.source_size or self.spec.sky_size
        push = np.zeros(32, np.float32)
        push[:28] = sky_model(sun_direction, turbidity).coefficients
        push.view(np.uint32)[28] = size

        def draw(cmd: Commands, pool: DescriptorPool, dst: ImageView) -> None:
            ds = pool.allocate(self.layout_no_src)
            wr = DescriptorWriter(self.device)
            wr.storage_image(ds, 1, dst)
            wr.update()
            cmd.bind_pipeline(self.sky)
            cmd.bind_set(0, ds)
            cmd.push(push)
            cmd.dispatch(*groups((size, size, 6), (8, 8, 1)))
        return self._bake(size, draw)

    def from_constant(self, rgb: tuple[float, float, float] = (0.0, 0.0, 0.0)) -> Environment:
        """A uniform environment of radiance `rgb` on 4 x 4 faces: black stands in where no
        environment lights the frame (set 2's samplers must always be written)."""
        pixels = np.broadcast_to(np.asarray(rgb, np.float32), (2, 4, 3))
        return self.from_panorama(np.ascontiguousarray(pixels), f"constant {tuple(rgb)}",
                                  size=4, irradiance_size=4)

    # --- the pre-filter ---------------------------------------------------------------------
    def _cube(self, size: int, mips: int, name: str) -> Image:
        vk = self.device.vk
        usage = (vk.VK_IMAGE_USAGE_SAMPLED_BIT | vk.VK_IMAGE_USAGE_STORAGE_BIT
                 | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT | vk.VK_IMAGE_USAGE_TRANSFER_DST_BIT)
        return Image(self.device, size, size, rgba16f_format(self.device), usage,
                     mip_levels=mips, name=name, layers=6, cube=True)

    def _bake(self, size: int, draw_source: Any, irradiance_size: int | None = None) -> Environment:
        device, spec = self.device, self.spec
        irr_size = irradiance_size or spec.irradiance_size
        lut = self.brdf_lut()
        t0 = time.perf_counter()
        spec_size = min(spec.specular_size, size)
        spec_mips = max(int(np.log2(spec_size)) - 1, 1)  # down to 4 x 4
        src_mips = int(np.log2(size)) + 1
        owned: list[Any] = []
        src = self._cube(size, src_mips, "env source")
        owned.append(src)
        spc = self._cube(spec_size, spec_mips, "env specular")
        owned.append(spc)
        irr = self._cube(irr_size, 1, "env irradiance")
        owned.append(irr)
        temp: list[Any] = []
        pool = DescriptorPool(device, [(self.layout, spec_mips + 1), (self.layout_2d, 1),
                                       (self.layout_no_src, 1)])
        temp.append(pool)
        try:
            src_store = ImageView(src, kind="2d_array", mips=1)
            temp.append(src_store)
            src_view = ImageView(src, kind="cube")
            owned.append(src_view)
            with device.one_time_commands() as raw:
                cmd = Commands(device, raw)
                cmd.image_barrier(src, "undefined", "general", "none", "compute", 0, 1)
                draw_source(cmd, pool, src_store)
                cmd.blit_mips(src, "shader_read", "compute")
                self._prefilter(cmd, pool, src_view, size, spc, spec_mips, irr, temp)
            bake_ms = (time.perf_counter() - t0) * 1e3
            spc_view = ImageView(spc, kind="cube")
            owned.append(spc_view)
            irr_view = ImageView(irr, kind="cube")
            owned.append(irr_view)
        except BaseException:
            for obj in reversed(owned):
                obj.destroy()
            raise
        finally:
            for obj in reversed(temp):
                obj.destroy()
        log.debug("environment: %d^2 source, %d^2 x %d specular levels, %.1f ms",
                  size, spec_size, spec_mips, bake_ms)
        return Environment(
            specular=SampledImage(spc, spc_view, self.cube_sampler),
            irradiance=SampledImage(irr, irr_view, self.cube_sampler),
            brdf_lut=lut,
            source=SampledImage(src, src_view, self.cube_sampler),
            max_lod=spec_mips - 1, bake_ms=bake_ms, _owned=tuple(owned))

    def _prefilter(self, cmd: Commands, pool: DescriptorPool, src_view: ImageView, size: int,
                   spc: Image, spec_mips: int, irr: Image, views: list[Any]) -> None:
        """Record the pre-filter of the source cube (`size`, sampled through `src_view`): GGX
        of roughness k / max_lod into level k of `spc`, the cosine convolution into `irr`.
        The image views it makes go into `views` (the caller destroys them once it has run)."""
        spec, spec_size, irr_size = self.spec, spc.width, irr.width
        cmd.image_barrier(spc, "undefined", "general", "none", "compute")
        cmd.image_barrier(irr, "undefined", "general", "none", "compute")
        for k in range(spec_mips):
            level = ImageView(spc, kind="2d_array", base_mip=k, mips=1)
            views.append(level)
            roughness = k / max(spec_mips - 1, 1)
            self._dispatch(cmd, pool, self.specular, src_view, level,
                           _push(np.float32(roughness), spec.specular_samples, size,
                                 max(spec_size >> k, 1)),
                           max(spec_size >> k, 1))
        irr_store = ImageView(irr, kind="2d_array")
        views.append(irr_store)
        self._dispatch(cmd, pool, self.irradiance, src_view, irr_store,
                       _push(spec.irradiance_samples, size, irr_size), irr_size)
        cmd.image_barrier(spc, "general", "shader_read", "compute", "sampled")
        cmd.image_barrier(irr, "general", "shader_read", "compute", "sampled")

    def _dispatch(self, cmd: Commands, pool: DescriptorPool, pipe: ComputePipeline,
                  src: ImageView, dst: ImageView, push: np.ndarray, size: int) -> None:
        ds = pool.allocate(self.layout)
        wr = DescriptorWriter(self.device)
        wr.sampler(ds, 0, src, self.cube_sampler)
        wr.storage_image(ds, 1, dst)
        wr.update()
        cmd.bind_pipeline(pipe)
        cmd.bind_set(0, ds)
        cmd.push(push)
        cmd.dispatch(*groups((size, size, 6), (8, 8, 1)))

    # --- the BRDF table ---------------------------------------------------------------------
    def lut_path(self) -> Path | None:
        if self.cache_dir is None:
            return None
        return Path(self.cache_dir) / f"brdf_lut-v{LUT_VERSION}-{LUT_SIZE}x{LUT_SIZE}-{LUT_SAMPLES}.npy"

    def brdf_lut(self) -> SampledImage:
        """The split-sum table on the GPU: from this process's copy, the cache file, or made
        by env_brdf_lut.comp (then read back and saved)."""
        if self._lut is not None:
            return self._lut
        table = _LUT_MEMORY.get((LUT_SIZE, LUT_SAMPLES))
        path = self.lut_path()
        if table is None and path is not None and path.is_file():
            try:
                loaded = np.load(path, allow_pickle=False)
                if loaded.shape == (LUT_SIZE, LUT_SIZE, 2) and np.isfinite(loaded).all():
                    table = loaded.astype(np.float32)
            except (OSError, ValueError) as exc:
                log.debug("%s: unreadable BRDF table, remade (%s)", path, exc)
        if table is None:
            table = self._make_lut()
        if path is not None and not path.is_file():  # made here or earlier in this process
            try:
                path.parent.mkdir(parents=True, exist_ok=True)
                with atomic_writer(path) as f:
                    np.save(f, table, allow_pickle=False)
            except OSError as exc:  # a cache that cannot be written is no error
                log.debug("%s: BRDF table not cached (%s)", path, exc)
        _LUT_MEMORY[(LUT_SIZE, LUT_SAMPLES)] = table
        rgba = np.zeros((LUT_SIZE, LUT_SIZE, 4), np.float32)
        rgba[..., :2] = table
        image = upload_rgba16f(self.device, rgba, name="brdf lut")
        self._lut = SampledImage(image, ImageView(image), self.lut_sampler)
        return self._lut

    def _make_lut(self) -> np.ndarray:
        """(LUT_SIZE, LUT_SIZE, 2) float32: [roughness row, n.v column] -> (A, B)."""
        device, vk = self.device, self.device.vk
        image = Image(device, LUT_SIZE, LUT_SIZE, rgba16f_format(device),
                      vk.VK_IMAGE_USAGE_STORAGE_BIT | vk.VK_IMAGE_USAGE_TRANSFER_SRC_BIT,
                      name="brdf lut (make)")
        view = ImageView(image, kind="2d_array")
        pool = DescriptorPool(device, [(self.layout_no_src, 1)])
        try:
            with device.one_time_commands() as raw:
                cmd = Commands(device, raw)
                cmd.image_barrier(image, "undefined", "general", "none", "compute")
                ds = pool.allocate(self.layout_no_src)
                wr = DescriptorWriter(device)
                wr.storage_image(ds, 1, view)
                wr.update()
                cmd.bind_pipeline(self.lut)
                cmd.bind_set(0, ds)
                cmd.push(_push(LUT_SAMPLES, LUT_SIZE))
                cmd.dispatch(*groups((LUT_SIZE, LUT_SIZE, 1), (8, 8, 1)))
            return read_rgba16f(device, image, 0, layout="general")[0, ..., :2].copy()
        finally:
            pool.destroy()
            view.destroy()
            image.destroy()


def _push(*values: Any) -> np.ndarray:
    """Push constants: floats stay floats (np.float32), ints become uint32; 16 bytes."""
    out = np.zeros(4, np.uint32)
    for i, v in enumerate(values):
        out[i] = np.float32(v).view(np.uint32) if isinstance(v, np.floating) else int(v)
    return out
