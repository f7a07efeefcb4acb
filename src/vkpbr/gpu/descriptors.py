"""Descriptor set layouts from a binding table, a pool, and a batched writer.

A layout is described as rows of (binding, kind, stages) in plain words: kind is "uniform",
"storage" (a storage buffer), "storage_image", or a combined image sampler: "sampler" or the
GLSL type it is declared as ("sampler2D", "samplerCube", "sampler2DArray", "sampler2DArrayShadow",
"samplerCubeArray", "samplerCubeArrayShadow": one Vulkan descriptor type, the view decides);
stages is a subset of "vertex", "fragment", "compute".
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any

from vkpbr.gpu.device import Device, DeviceObject

__all__ = ["BindingSpec", "DescriptorSetLayout", "DescriptorPool", "DescriptorWriter"]


@dataclass(frozen=True)
class BindingSpec:
    binding: int
    kind: str  # "uniform" | "storage" | "storage_image" | "sampler" (or a GLSL sampler type)
    stages: tuple[str, ...]
    name: str = ""


def _descriptor_type(vk: Any, kind: str) -> int:
    if kind.startswith("sampler"):
        return vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER
    return {
        "uniform": vk.VK_DESCRIPTOR_TYPE_UNIFORM_BUFFER,
        "storage": vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
        "storage_image": vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE,
    }[kind]


def _stage_flags(vk: Any, stages: Sequence[str]) -> int:
    bits = {"vertex": vk.VK_SHADER_STAGE_VERTEX_BIT, "fragment": vk.VK_SHADER_STAGE_FRAGMENT_BIT,
            "compute": vk.VK_SHADER_STAGE_COMPUTE_BIT}
    flags = 0
    for s in stages:
        flags |= bits[s]
    return flags


class DescriptorSetLayout(DeviceObject):
    _destroy_fn = "vkDestroyDescriptorSetLayout"

    def __init__(self, device: Device, bindings: Sequence[BindingSpec]) -> None:
        vk = device.vk
        self.device = device
        self.bindings = tuple(bindings)
        rows = [(b.binding, _descriptor_type(vk, b.kind), _stage_flags(vk, b.stages))
                for b in self.bindings]
        self.handle = self._kept_handle(tuple(rows), lambda: vk.vkCreateDescriptorSetLayout(
            device.handle,
            vk.VkDescriptorSetLayoutCreateInfo(pBindings=[
                vk.VkDescriptorSetLayoutBinding(binding=b, descriptorType=t, descriptorCount=1,
                                                stageFlags=f)
                for b, t, f in rows]),
            None))
        device.track(self)



class DescriptorPool(DeviceObject):
    """A pool sized for `max_sets` sets of the given layouts' mix of descriptors."""

    _destroy_fn = "vkDestroyDescriptorPool"

    def __init__(
        self, device: Device, layouts_and_counts: Sequence[tuple[DescriptorSetLayout, int]]
    ) -> None:
        vk = device.vk
        self.device = device
        totals: dict[int, int] = {}  # by descriptor type: the sampler kinds share one
        max_sets = 0
        for layout, count in layouts_and_counts:
            max_sets += count
            for b in layout.bindings:
                t = _descriptor_type(vk, b.kind)
                totals[t] = totals.get(t, 0) + count
        self.handle = vk.vkCreateDescriptorPool(
            device.handle,
            vk.VkDescriptorPoolCreateInfo(
                maxSets=max(max_sets, 1),
                pPoolSizes=[
                    vk.VkDescriptorPoolSize(type=kind, descriptorCount=n)
                    for kind, n in totals.items()
                ],
            ),
            None,
        )
        device.track(self)

    def allocate(self, layout: DescriptorSetLayout) -> Any:
        return self.allocate_many(layout, 1)[0]

    def allocate_many(self, layout: DescriptorSetLayout, count: int) -> list[Any]:
        """`count` sets of `layout` in one call (a call into the driver each set had cost a
        scene's first frame one per material)."""
        vk = self.device.vk
        return list(vk.vkAllocateDescriptorSets(
            self.device.handle,
            vk.VkDescriptorSetAllocateInfo(
                descriptorPool=self.handle, pSetLayouts=[layout.handle] * count
            ),
        ))



class DescriptorWriter:
    """Collect writes, then `update()` them in one vkUpdateDescriptorSets call.

    The writes are kept as plain tuples and made into C structs once, at `update`, straight
    through cffi (`ffi.new` of the arrays, their fields set in place) and the loader's entry
    point: the binding's struct factories cost ~30 us a descriptor (a material's set is 17
    of them, and a scene change writes every set it draws with: issue 32), the same call
    made so costs ~3. The Vulkan call and its arguments are the same as the binding's.
    """

    _IMAGE, _BUFFER = 0, 1

    def __init__(self, device: Device) -> None:
        self.device = device
        # (dst set, binding, descriptor type, image or buffer info kind, info fields)
        self._writes: list[tuple[Any, int, int, int, tuple]] = []

    def uniform(self, dst_set: Any, binding: int, buffer: Any, size: int, offset: int = 0,
                kind: str = "uniform") -> None:
        """Point a uniform (or, with kind="storage", a storage) buffer binding at
        `size` bytes of `buffer` from `offset`."""
        self._writes.append((dst_set, binding, _descriptor_type(self.device.vk, kind),
                             self._BUFFER, (buffer.handle, offset, size)))

    def sampler(self, dst_set: Any, binding: int, view: Any, sampler: Any) -> None:
        vk = self.device.vk
        self._writes.append((dst_set, binding, vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER,
                             self._IMAGE, (sampler.handle, view.handle,
                                           vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL)))

    def storage(self, dst_set: Any, binding: int, buffer: Any, size: int | None = None,
                offset: int = 0) -> None:
        """A storage buffer (`size` None: the whole buffer from `offset`)."""
        self._writes.append((dst_set, binding, self.device.vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER,
                             self._BUFFER, (buffer.handle, offset,
                                            buffer.size - offset if size is None else size)))

    def storage_image(self, dst_set: Any, binding: int, view: Any) -> None:
        """A storage image, accessed in the GENERAL layout."""
        vk = self.device.vk
        self._writes.append((dst_set, binding, vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, self._IMAGE,
                             (None, view.handle, vk.VK_IMAGE_LAYOUT_GENERAL)))

    def update(self) -> None:
        writes, self._writes = self._writes, []
        if not writes:
            return
        vk = self.device.vk
        ffi, n = vk.ffi, len(writes)
        images = sum(1 for w in writes if w[3] == self._IMAGE)
        structs = ffi.new("VkWriteDescriptorSet[]", n)
        image_infos = ffi.new("VkDescriptorImageInfo[]", max(images, 1))
        buffer_infos = ffi.new("VkDescriptorBufferInfo[]", max(n - images, 1))
        stype = vk.VK_STRUCTURE_TYPE_WRITE_DESCRIPTOR_SET
        i = b = 0
        for out, (dst_set, binding, dtype, info_kind, fields) in zip(structs, writes, strict=True):
            out.sType, out.dstSet, out.dstBinding = stype, dst_set, binding
            out.descriptorCount, out.descriptorType = 1, dtype
            if info_kind == self._IMAGE:
                info = image_infos[i]
                if fields[0] is not None:
                    info.sampler = fields[0]
                info.imageView, info.imageLayout = fields[1], fields[2]
                out.pImageInfo = image_infos + i
                i += 1
            else:
                info = buffer_infos[b]
                info.buffer, info.offset, info.range = fields
                out.pBufferInfo = buffer_infos + b
                b += 1
        # (void: nothing to check; the arrays live until it returns)
        vk.lib.vkUpdateDescriptorSets(self.device.handle, n, structs, 0, ffi.NULL)
