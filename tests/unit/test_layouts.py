"""Uniform layouts: Python's std140 offsets against the compiled shaders' own offsets, and the
committed SPIR-V and generated GLSL against a fresh compile (stale files fail)."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import numpy as np
import pytest

from vkpbr.render import codegen
from vkpbr.render import layouts as L


def spirv_member_offsets(path: Path) -> dict[str, dict[str, int]]:
    """{struct name: {member name: offset}} read from a SPIR-V module's decorations."""
    data = path.read_bytes()
    words = struct.unpack(f"<{len(data) // 4}I", data)
    names: dict[int, str] = {}
    member_names: dict[tuple[int, int], str] = {}
    offsets: dict[tuple[int, int], int] = {}
    i = 5  # skip the header
    while i < len(words):
        count, opcode = words[i] >> 16, words[i] & 0xFFFF
        ops = words[i + 1 : i + count]
        def text(ws: tuple[int, ...]) -> str:
            return b"".join(struct.pack("<I", w) for w in ws).split(b"\0")[0].decode()
        if opcode == 5:  # OpName
            names[ops[0]] = text(ops[1:])
        elif opcode == 6:  # OpMemberName
            member_names[(ops[0], ops[1])] = text(ops[2:])
        elif opcode == 72 and ops[2] == 35:  # OpMemberDecorate ... Offset
            offsets[(ops[0], ops[1])] = ops[3]
        i += count
    out: dict[str, dict[str, int]] = {}
    for (type_id, member), offset in offsets.items():
        if (type_id, member) in member_names:  # unnamed structs (e.g. arrays) are skipped
            out.setdefault(names.get(type_id, str(type_id)), {})[member_names[(type_id, member)]] = offset
    return out


def test_std140_offsets_match_compiled_shaders() -> None:
    found: dict[str, dict[str, int]] = {}
    for spv in codegen.SPV_DIR.glob("*.spv"):
        found.update(spirv_member_offsets(spv))
    for block in (*L.BLOCKS, L.VIEW_RECORD):
        assert block.name in found, f"{block.name} is used by no shader"
        assert found[block.name] == {k: v for k, v in block.offsets.items() if k in found[block.name]}
        # Every member the shader declares is one Python knows, at the same offset.
        assert set(found[block.name]) == set(block.offsets)


def test_std140_rules() -> None:
    assert L.LIGHTING.offsets == {"light_count": 0, "mode": 4, "flags": 8, "env_intensity": 12,
                                  "env_rotation": 16, "ambient_color": 32}
    assert L.LIGHTING.size == 48
    assert L.LIGHT_RECORD.size == 80 and L.LIGHT_RECORD.dtype.itemsize == 80
    # The views: VP and its inverse (the compute path's pixel rays), eye and near, forward and
    # far, intrinsics, viewport, layer; the uint pads the record to 208 bytes (std140 and
    # std430 alike: the array's stride).
    assert L.VIEW_RECORD.offsets == {"VP": 0, "inv_VP": 64, "eye_near": 128, "forward_far": 144,
                                     "intrinsics": 160, "viewport": 176, "layer": 192,
                                     "instance_base": 196, "factor_base": 200,
                                         "shadow_base": 204}
    assert L.VIEW_RECORD.size == L.VIEW_RECORD.dtype.itemsize == 208
    assert L.PUSH.size <= 128  # the guaranteed minimum maxPushConstantsSize
    assert L.MATERIAL.dtype.itemsize == L.MATERIAL.size


def test_generated_glsl_is_current() -> None:
    assert codegen.GENERATED.read_text() == codegen.generated_glsl(), (
        "shaders/generated.glsl is stale: run `python -m vkpbr.render.codegen`")


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed (scripts/setup.sh installs it)")
def test_committed_spirv_is_current(tmp_path: Path) -> None:
    fresh = codegen.compile_all(tmp_path, write_generated=False)
    stale = []
    for f in fresh:
        committed = codegen.SPV_DIR / f.name
        a, b = f.read_bytes(), committed.read_bytes() if committed.exists() else b""
        # Word 2 of the header names the generator version; everything else must match.
        if a[:8] + a[12:] != b[:8] + b[12:]:
            stale.append(f.name)
    assert not stale, f"stale SPIR-V {stale}: run `python -m vkpbr.render.codegen` and commit"
    assert {p.name for p in codegen.SPV_DIR.glob('*.spv')} == {f.name for f in fresh}


@pytest.mark.parametrize("block", [L.VIEW_RECORD, L.SETTINGS, L.LIGHTING, L.LIGHT_RECORD],
                         ids=lambda b: b.name)
def test_struct_packer_writes_the_numpy_layout(block) -> None:  # noqa: ANN001
    """The per-frame struct packer and the structured dtype put every member at the same
    bytes (random values; mat4 flattened column by column)."""
    rng = np.random.default_rng(7)
    arr = block.zeros()
    flat: list = []
    for name, glsl in block.fields:
        value = rng.integers(0, 1000, arr[name].shape) if glsl in ("int", "uint", "uvec4") else \
            rng.random(arr[name].shape).astype(np.float32)
        arr[name] = value
        flat += np.asarray(value).reshape(-1).tolist()
    assert block.packer.size == block.size
    buf = bytearray(block.size)
    block.packer.pack_into(buf, 0, *flat)
    assert bytes(buf) == arr.tobytes()


def test_every_output_has_its_place_in_the_output_images() -> None:
    """OUTPUT_PARTS (render/outputs.py) names, for every dataset output but the colour, an
    image of OUTPUT_IMAGES and channels that image has."""
    from vkpbr.render import layouts as L
    from vkpbr.render.outputs import OUTPUT_PARTS, OUTPUTS

    assert set(OUTPUT_PARTS) == set(OUTPUTS) - {"color"}
    for name, (image, channels) in OUTPUT_PARTS.items():
        count = L.OUTPUT_IMAGES[image][3]
        picked = range(count)[channels]
        assert (len(picked) if isinstance(picked, range) else 1) > 0, name
        assert (max(picked) if isinstance(picked, range) else picked) < count, name
