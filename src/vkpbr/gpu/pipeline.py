"""Graphics pipelines from a frozen `PipelineSpec`, shader modules from committed SPIR-V.

`build_pipeline` is the only place that turns a spec into Vulkan create-info structs. Variants
are derived with `dataclasses.replace(opaque, cull="none", ...)`, as vkguide builds its
transparent pipeline from its opaque one. Pipelines use dynamic rendering (no render pass
objects) and dynamic viewport/scissor, so one pipeline serves every image size.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from vkpbr.errors import ShaderError
from vkpbr.gpu.descriptors import DescriptorSetLayout
from vkpbr.gpu.device import Device, DeviceObject
from vkpbr.gpu.kept import address, file_key
from vkpbr.gpu.pipeline_cache import Feedback

__all__ = ["VertexStream", "PipelineSpec", "PipelineLayout", "Pipeline", "ShaderModule", "shader_key"]


@dataclass(frozen=True)
class VertexStream:
    """One non-interleaved vertex attribute: its own buffer binding."""

    location: int
    binding: int
    format: str  # "vec2" | "vec3" | "vec4" | "uint" | "unorm16x4"
    stride: int | None = None  # bytes between vertices; None: the format's size, 0: one value for all


_FORMATS = {
    "vec2": ("VK_FORMAT_R32G32_SFLOAT", 8),
    "vec3": ("VK_FORMAT_R32G32B32_SFLOAT", 12),
    "vec4": ("VK_FORMAT_R32G32B32A32_SFLOAT", 16),
    "uint": ("VK_FORMAT_R32_UINT", 4),
    "unorm16x4": ("VK_FORMAT_R16G16B16A16_UNORM", 8),  # read as vec4 in [0, 1]
}


@dataclass(frozen=True)
class PipelineSpec:
    vertex_shader: str  # SPIR-V file name under the shader folder
    fragment_shader: str | None  # None: depth only (a depth pre-pass)
    streams: tuple[VertexStream, ...]
    color_format: int | None  # None: no colour attachment (depth-only passes: shadow maps)
    depth_format: int
    samples: int = 1
    cull: str = "back"  # back | none
    depth_test: bool = True
    depth_write: bool = True
    # Reversed-Z by default (depth 1 at the near plane, 0 infinitely far): nearer is greater.
    depth_compare: str = "greater_or_equal"  # | "less_or_equal" | "equal" | "always"
    blend: bool = False  # premultiplied-free "over" blending of the colour attachment
    color_write: bool = True  # False: the colour attachment is left untouched
    # (constant, slope) depth bias factors (Vulkan's; negative pushes depth away under
    # reversed-Z); None: no bias.
    depth_bias: tuple[float, float] | None = None
    # The fragment shader's specialisation constants: (constant_id, 32-bit value) pairs; the
    # others keep the shader's defaults.
    fragment_constants: tuple[tuple[int, int], ...] = ()


def shader_key(path: Path) -> tuple[str, int, int]:
    """A shader file's key (gpu/kept.py file_key); a missing file raises as ShaderModule does."""
    try:
        return file_key(path)
    except OSError as exc:
        raise ShaderError(f"{path}: cannot read SPIR-V ({exc.strerror})") from None


class ShaderModule(DeviceObject):
    _destroy_fn = "vkDestroyShaderModule"

    def __init__(self, device: Device, path: Path) -> None:
        vk = device.vk
        self.device = device
        try:
            code = path.read_bytes()
        except OSError as exc:
            raise ShaderError(f"{path}: cannot read SPIR-V ({exc.strerror})") from None
        if len(code) % 4 or code[:4] != b"\x03\x02\x23\x07":
            raise ShaderError(f"{path}: not a SPIR-V module")
        # codeSize is not inferred by the binding: leaving it out crashes the driver.
        self.handle = vk.vkCreateShaderModule(
            device.handle, vk.VkShaderModuleCreateInfo(codeSize=len(code), pCode=code), None
        )
        device.track(self)



class PipelineLayout(DeviceObject):
    _destroy_fn = "vkDestroyPipelineLayout"

    def __init__(
        self,
        device: Device,
        set_layouts: list[DescriptorSetLayout],
        push_constant_bytes: int = 0,
        stages: tuple[str, ...] = ("vertex", "fragment"),
    ) -> None:
        vk = device.vk
        self.device = device
        bits = {"vertex": vk.VK_SHADER_STAGE_VERTEX_BIT, "fragment": vk.VK_SHADER_STAGE_FRAGMENT_BIT,
                "compute": vk.VK_SHADER_STAGE_COMPUTE_BIT}
        # The stages that see the push constants (Commands.push pushes to these).
        self.push_stages = 0
        for st in stages:
            self.push_stages |= bits[st]
        ranges = []
        if push_constant_bytes:
            ranges.append(
                vk.VkPushConstantRange(
                    stageFlags=self.push_stages,
                    offset=0,
                    size=push_constant_bytes,
                )
            )
        key = (tuple(address(s.handle, vk.ffi) for s in set_layouts), push_constant_bytes,
               self.push_stages)
        self.handle = self._kept_handle(key, lambda: vk.vkCreatePipelineLayout(
            device.handle,
            vk.VkPipelineLayoutCreateInfo(
                pSetLayouts=[s.handle for s in set_layouts],
                pPushConstantRanges=ranges or None,
                pushConstantRangeCount=len(ranges),
            ),
            None,
        ))
        device.track(self)



class Pipeline(DeviceObject):
    _destroy_fn = "vkDestroyPipeline"

    def __init__(
        self, device: Device, spec: PipelineSpec, layout: PipelineLayout, shader_dir: Path
    ) -> None:
        self.device = device
        self.spec = spec
        self.layout = layout
        shaders = [shader_dir / s for s in (spec.vertex_shader, spec.fragment_shader) if s]
        key = (spec, address(layout.handle, device.vk.ffi), *map(shader_key, shaders))
        self.handle = self._kept_handle(key, lambda: self._build(spec, layout, shader_dir))
        device.track(self)

    def _build(self, spec: PipelineSpec, layout: PipelineLayout, shader_dir: Path) -> Any:
        """The pipeline's handle, with its shader modules made for the call only."""
        vert = ShaderModule(self.device, shader_dir / spec.vertex_shader)
        frag = None
        try:
            if spec.fragment_shader is not None:
                frag = ShaderModule(self.device, shader_dir / spec.fragment_shader)
            return self._create(spec, layout, vert, frag)
        finally:
            vert.destroy()
            if frag is not None:
                frag.destroy()

    def _create(self, spec: PipelineSpec, layout: PipelineLayout, vert: Any, frag: Any | None) -> Any:
        vk = self.device.vk
        stages = [
            vk.VkPipelineShaderStageCreateInfo(
                stage=vk.VK_SHADER_STAGE_VERTEX_BIT, module=vert.handle, pName="main"
            ),
        ]
        # (the constants' bytes stay referenced until the create call returns)
        data = struct.pack(f"<{len(spec.fragment_constants)}I",
                           *(int(v) & 0xFFFFFFFF for _, v in spec.fragment_constants))
        if frag is not None:
            constants = None
            if spec.fragment_constants:
                constants = vk.VkSpecializationInfo(
                    pMapEntries=[vk.VkSpecializationMapEntry(constantID=c, offset=4 * i, size=4)
                                 for i, (c, _) in enumerate(spec.fragment_constants)],
                    dataSize=len(data), pData=vk.ffi.from_buffer(data))
            stages.append(vk.VkPipelineShaderStageCreateInfo(
                stage=vk.VK_SHADER_STAGE_FRAGMENT_BIT, module=frag.handle, pName="main",
                pSpecializationInfo=constants))
        bindings = [
            vk.VkVertexInputBindingDescription(
                binding=s.binding, stride=_FORMATS[s.format][1] if s.stride is None else s.stride,
                inputRate=vk.VK_VERTEX_INPUT_RATE_VERTEX,
            )
            for s in spec.streams
        ]
        attributes = [
            vk.VkVertexInputAttributeDescription(
                location=s.location, binding=s.binding,
                format=getattr(vk, _FORMATS[s.format][0]), offset=0,
            )
            for s in spec.streams
        ]
        cull = {"back": vk.VK_CULL_MODE_BACK_BIT, "none": vk.VK_CULL_MODE_NONE}[spec.cull]
        all_rgba = (
            vk.VK_COLOR_COMPONENT_R_BIT | vk.VK_COLOR_COMPONENT_G_BIT
            | vk.VK_COLOR_COMPONENT_B_BIT | vk.VK_COLOR_COMPONENT_A_BIT
        )
        blend = vk.VkPipelineColorBlendAttachmentState(
            blendEnable=vk.VK_TRUE if spec.blend else vk.VK_FALSE,
            srcColorBlendFactor=vk.VK_BLEND_FACTOR_SRC_ALPHA,
            dstColorBlendFactor=vk.VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
            colorBlendOp=vk.VK_BLEND_OP_ADD,
            srcAlphaBlendFactor=vk.VK_BLEND_FACTOR_ONE,
            dstAlphaBlendFactor=vk.VK_BLEND_FACTOR_ONE_MINUS_SRC_ALPHA,
            alphaBlendOp=vk.VK_BLEND_OP_ADD,
            # colorWriteMask defaults to 0 in the binding: nothing would be written.
            colorWriteMask=all_rgba if spec.color_write else 0,
        )
        has_color = spec.color_format is not None
        feedback = Feedback(self.device)  # the build goes through the device's pipeline cache
        rendering = vk.VkPipelineRenderingCreateInfo(
            pNext=feedback.info,
            colorAttachmentCount=1 if has_color else 0,
            pColorAttachmentFormats=[spec.color_format] if has_color else None,
            depthAttachmentFormat=spec.depth_format,
        )
        bias = spec.depth_bias
        info = vk.VkGraphicsPipelineCreateInfo(
            pNext=rendering,
            pStages=stages,
            pVertexInputState=vk.VkPipelineVertexInputStateCreateInfo(
                pVertexBindingDescriptions=bindings, pVertexAttributeDescriptions=attributes
            ),
            pInputAssemblyState=vk.VkPipelineInputAssemblyStateCreateInfo(
                topology=vk.VK_PRIMITIVE_TOPOLOGY_TRIANGLE_LIST
            ),
            pViewportState=vk.VkPipelineViewportStateCreateInfo(viewportCount=1, scissorCount=1),
            pRasterizationState=vk.VkPipelineRasterizationStateCreateInfo(
                polygonMode=vk.VK_POLYGON_MODE_FILL,
                cullMode=cull,
                frontFace=vk.VK_FRONT_FACE_COUNTER_CLOCKWISE,
                lineWidth=1.0,
                depthBiasEnable=vk.VK_FALSE if bias is None else vk.VK_TRUE,
                depthBiasConstantFactor=0.0 if bias is None else bias[0],
                depthBiasSlopeFactor=0.0 if bias is None else bias[1],
            ),
            pMultisampleState=vk.VkPipelineMultisampleStateCreateInfo(
                rasterizationSamples=spec.samples
            ),
            pDepthStencilState=vk.VkPipelineDepthStencilStateCreateInfo(
                depthTestEnable=vk.VK_TRUE if spec.depth_test else vk.VK_FALSE,
                depthWriteEnable=vk.VK_TRUE if spec.depth_write else vk.VK_FALSE,
                depthCompareOp=getattr(vk, f"VK_COMPARE_OP_{spec.depth_compare.upper()}"),
            ),
            pColorBlendState=vk.VkPipelineColorBlendStateCreateInfo(
                pAttachments=[blend] if has_color else None),
            pDynamicState=vk.VkPipelineDynamicStateCreateInfo(
                pDynamicStates=[vk.VK_DYNAMIC_STATE_VIEWPORT, vk.VK_DYNAMIC_STATE_SCISSOR]
            ),
            layout=layout.handle,
        )
        return feedback.build("graphics", info, "+".join(
            s for s in (spec.vertex_shader, spec.fragment_shader) if s))

