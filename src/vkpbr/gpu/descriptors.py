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
        vk = self.device.vk
        return vk.vkAllocateDescriptorSets(
            self.device.handle,
            vk.VkDescriptorSetAllocateInfo(
                descriptorPool=self.handle, pSetLayouts=[layout.handle]
            ),
        )[0]



class DescriptorWriter:
    """Collect writes, then `update()` them in one vkUpdateDescriptorSets call.

    The info structs are kept referenced in `self._keep` until the update returns.
    """

    def __init__(self, device: Device) -> None:
        self.device = device
        self._writes: list[Any] = []
        self._keep: list[Any] = []

    def uniform(self, dst_set: Any, binding: int, buffer: Any, size: int, offset: int = 0,
                kind: str = "uniform") -> None:
        """Point a uniform (or, with kind="storage", a storage) buffer binding at
        `size` bytes of `buffer` from `offset`."""
        vk = self.device.vk
        info = vk.VkDescriptorBufferInfo(buffer=buffer.handle, offset=offset, range=size)
        self._keep.append(info)
        self._writes.append(
            vk.VkWriteDescriptorSet(
                dstSet=dst_set, dstBinding=binding, descriptorCount=1,
                descriptorType=_descriptor_type(vk, kind), pBufferInfo=[info],
            )
        )

    def sampler(self, dst_set: Any, binding: int, view: Any, sampler: Any) -> None:
        vk = self.device.vk
        info = vk.VkDescriptorImageInfo(
            sampler=sampler.handle, imageView=view.handle,
            imageLayout=vk.VK_IMAGE_LAYOUT_SHADER_READ_ONLY_OPTIMAL,
        )
        self._keep.append(info)
        self._writes.append(
            vk.VkWriteDescriptorSet(
                dstSet=dst_set, dstBinding=binding, descriptorCount=1,
                descriptorType=vk.VK_DESCRIPTOR_TYPE_COMBINED_IMAGE_SAMPLER, pImageInfo=[info],
            )
        )

    def storage(self, dst_set: Any, binding: int, buffer: Any, size: int | None = None,
                offset: int = 0) -> None:
        """A storage buffer (`size` None: the whole buffer from `offset`)."""
        vk = self.device.vk
        info = vk.VkDescriptorBufferInfo(buffer=buffer.handle, offset=offset,
                                         range=buffer.size - offset if size is None else size)
        self._keep.append(info)
        self._writes.append(
            vk.VkWriteDescriptorSet(
                dstSet=dst_set, dstBinding=binding, descriptorCount=1,
                descriptorType=vk.VK_DESCRIPTOR_TYPE_STORAGE_BUFFER, pBufferInfo=[info],
            )
        )

    def storage_image(self, dst_set: Any, binding: int, view: Any) -> None:
        """A storage image, accessed in the GENERAL layout."""
        vk = self.device.vk
        info = vk.VkDescriptorImageInfo(imageView=view.handle,
                                        imageLayout=vk.VK_IMAGE_LAYOUT_GENERAL)
        self._keep.append(info)
        self._writes.append(
            vk.VkWriteDescriptorSet(
                dstSet=dst_set, dstBinding=binding, descriptorCount=1,
                descriptorType=vk.VK_DESCRIPTOR_TYPE_STORAGE_IMAGE, pImageInfo=[info],
            )
        )

    def update(self) -> None:
        if self._writes:
            vk = self.device.vk
            vk.vkUpdateDescriptorSets(self.device.handle, len(self._writes), self._writes, 0, None)
        self._writes.clear()
        self._keep.clear()
