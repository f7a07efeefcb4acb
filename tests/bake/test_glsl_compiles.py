# Compile-checks shaders/tbn_decode.glsl (the GLSL mirror of bake/frames.py) when glslc exists.
from __future__ import annotations

import shutil
import subprocess
from pathlib import Path

import pytest

import vkpbr

SHADERS = Path(vkpbr.__file__).parent / "shaders"

TEST_SHADER = """#version 450
#extension GL_GOOGLE_include_directive : require
#include "tbn_decode.glsl"
#include "tbn_decode.glsl"
layout(location = 0) in uint packed_frame;
layout(location = 1) in vec4 qtangent;
layout(location = 0) out vec3 o_value;
void main() {
    mat3 a = tbn_from_qtangent(qtangent_unpack(packed_frame));
    mat3 b = tbn_from_qtangent(qtangent);
    o_value = a[0] + a[1] + a[2] + b[1];
    gl_Position = vec4(b[2], 1.0);
}
"""


@pytest.mark.skipif(shutil.which("glslc") is None, reason="glslc not installed")
def test_tbn_decode_compiles(tmp_path: Path) -> None:
    src = tmp_path / "t.vert"
    src.write_text(TEST_SHADER)
    result = subprocess.run(["glslc", "-I", str(SHADERS), str(src), "-o", str(tmp_path / "t.spv")],
                            capture_output=True, text=True, check=False)
    assert result.returncode == 0, result.stderr
