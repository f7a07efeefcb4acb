"""Generate shaders/generated.glsl from render/layouts.py and compile every shader variant.

`python -m vkpbr.render.codegen` rewrites generated.glsl and recompiles the committed SPIR-V
with glslc. Users never need this (the SPIR-V is committed); tests call `compile_all` into a
temporary folder and fail when a committed file is stale.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from collections.abc import Callable
from concurrent.futures import ThreadPoolExecutor
from dataclasses import dataclass
from pathlib import Path

from vkpbr.errors import ShaderError
from vkpbr.render import layouts as L

SHADER_DIR = Path(__file__).resolve().parent.parent / "shaders"
SPV_DIR = SHADER_DIR / "spv"
GENERATED = SHADER_DIR / "generated.glsl"


@dataclass(frozen=True)
class Variant:
    output: str  # file name under spv/
    source: str  # GLSL file under shaders/
    defines: tuple[tuple[str, int], ...] = ()


# The post steps' shaders (render/post.py, render/post_stage.py): one build of each
# shaders/post_*.comp / .vert / .frag, found by name.
_POST_KERNELS = tuple(Variant(f"{p.name}.spv", p.name) for p in sorted(SHADER_DIR.glob("post_*"))
                      if p.suffix in (".comp", ".vert", ".frag"))

VARIANTS: tuple[Variant, ...] = (
    *_POST_KERNELS,
    # The bloom's steps between levels of other than 2:1 (odd sizes): exact area weights
    # (post_bloom.comp ODD_LEVELS); the 2:1 steps keep their constant weights' kernel.
    Variant("post_bloom_odd.comp.spv", "post_bloom.comp", (("ODD_LEVELS", 1),)),
    *(Variant(f"pbr_{m.name.lower()}.vert.spv", "pbr.vert", (("TBN_MODE", int(m)),)) for m in L.TbnMode),
    Variant("pbr_opaque.frag.spv", "pbr.frag", (("ALPHA_MASK", 0),)),
    Variant("pbr_mask.frag.spv", "pbr.frag", (("ALPHA_MASK", 1),)),
    # The compute path: its visibility pass (pbr.frag's coverage), classification, shading.
    Variant("pbr_vis_opaque.frag.spv", "pbr.frag", (("ALPHA_MASK", 0), ("VISIBILITY", 1))),
    Variant("pbr_vis_mask.frag.spv", "pbr.frag", (("ALPHA_MASK", 1), ("VISIBILITY", 1))),
    *(Variant(f"shade_{m.name.lower()}.comp.spv", "shade.comp",
              (("TBN_MODE", int(m)), ("COMPUTE_SHADING", 1))) for m in L.TbnMode),
    *(Variant(f"shade_batch_{m.name.lower()}.comp.spv", "shade.comp",
              (("TBN_MODE", int(m)), ("COMPUTE_SHADING", 1), ("BATCH", 1))) for m in L.TbnMode),
    *(Variant(f"background_{name}.comp.spv", "background.comp",
              (("COMPUTE_SHADING", 1), ("BATCH", batch))) for name, batch in (("view", 0), ("batch", 1))),
    *(Variant(f"shade_outputs_{m.name.lower()}.comp.spv", "shade.comp",
              (("TBN_MODE", int(m)), ("COMPUTE_SHADING", 1), ("OUTPUTS", 1))) for m in L.TbnMode),
    # ... and a compute batch's (render/batch_path.py): each pixel's view is its tile's.
    *(Variant(f"shade_batch_outputs_{m.name.lower()}.comp.spv", "shade.comp",
              (("TBN_MODE", int(m)), ("COMPUTE_SHADING", 1), ("OUTPUTS", 1), ("BATCH", 1)))
      for m in L.TbnMode),
    *(Variant(f"classify_{name}{'' if agg else '_plain'}.comp.spv", "classify.comp",
              (("COMPUTE_SHADING", 1), ("KERNEL", k), ("AGGREGATE", agg)))
      for k, name in ((1, "count"), (2, "offsets"), (3, "scatter")) for agg in (1, 0)
      if agg or k != 2),
    # The transmission's copy of the opaque scene on the compute path (render/transmission.py):
    # linear radiance whatever the frame's target encodes.
    *(Variant(f"shade_copy_{m.name.lower()}.comp.spv", "shade.comp",
              (("TBN_MODE", int(m)), ("COMPUTE_SHADING", 1), ("OPAQUE_COPY", 1))) for m in L.TbnMode),
    *(Variant(f"classify_count{'' if agg else '_plain'}_copy.comp.spv", "classify.comp",
              (("COMPUTE_SHADING", 1), ("KERNEL", 1), ("AGGREGATE", agg), ("OPAQUE_COPY", 1)))
      for agg in (1, 0)),
    # Screen-space ambient occlusion (render/ao.py): GTAO, then its spatial denoise.
    # GTAO's main pass a build per preset's slices x steps (render/ao.py PRESETS: unrolled).
    Variant("ao_prefilter.comp.spv", "ao_prefilter.comp"),
    # (from the compute rasteriser's depth buffer: no copy into the depth image for GTAO)
    Variant("ao_prefilter_buffer.comp.spv", "ao_prefilter.comp", (("AO_DEPTH_BUFFER", 1),)),
    *(Variant(f"ao_gtao_{n}x{n}{suffix}.comp.spv", "ao_gtao.comp",
              (("AO_SLICES", n), ("AO_STEPS", n), *layered))
      for n in (3, 2) for suffix, layered in (("", ()), ("_layers", (("AO_LAYERED", 1),)))),
    Variant("ao_denoise.comp.spv", "ao_denoise.comp"),
    Variant("ao_upsample.comp.spv", "ao_upsample.comp"),
    # ... and their layered batch's builds (a view a layer of array images).
    *(Variant(f"{n}_layers.comp.spv", f"{n}.comp", (("AO_LAYERED", 1),))
      for n in ("ao_prefilter", "ao_denoise", "ao_upsample")),
    # Its depth pre-pass's masked rows where a frame has no visibility image (MSAA, windows).
    Variant("pbr_depth_mask.frag.spv", "pbr.frag", (("ALPHA_MASK", 1), ("DEPTH_ONLY", 1))),
    Variant("pbr_batch_depth_mask.frag.spv", "pbr.frag",
            (("ALPHA_MASK", 1), ("DEPTH_ONLY", 1), ("BATCH", 1))),
    # Shadow-map passes (render/shadows.py): depth only, or cut out by the base colour's alpha.
    Variant("shadow_opaque.vert.spv", "shadow.vert", (("ALPHA_MASK", 0),)),
    Variant("shadow_mask.vert.spv", "shadow.vert", (("ALPHA_MASK", 1),)),
    Variant("shadow_mask.frag.spv", "shadow_mask.frag"),
    Variant("hud.vert.spv", "hud.vert"),  # the viewer's text overlay (app/hud.py)
    Variant("hud.frag.spv", "hud.frag"),
    # The environment (render/environment.py): source cube, pre-filter, BRDF table, sky.
    *(Variant(f"{n}.comp.spv", f"{n}.comp") for n in (
        "env_equirect", "env_sky", "env_specular", "env_irradiance", "env_brdf_lut")),
    Variant("background.vert.spv", "background.vert"),
    # Batched views (render/batch.py): the frame's shaders reading each instance's view,
    # and the per-view culling kernel writing the instanced indirect draws.
    *(Variant(f"pbr_batch_{m.name.lower()}.vert.spv", "pbr.vert", (("TBN_MODE", int(m)), ("BATCH", 1)))
      for m in L.TbnMode),
    # ... and the compute batch's blended draws: each view into its tile of the atlas.
    *(Variant(f"pbr_atlas_{m.name.lower()}.vert.spv", "pbr.vert",
              (("TBN_MODE", int(m)), ("BATCH", 1), ("ATLAS", 1))) for m in L.TbnMode),
    Variant("pbr_batch_opaque.frag.spv", "pbr.frag", (("ALPHA_MASK", 0), ("BATCH", 1))),
    Variant("pbr_batch_mask.frag.spv", "pbr.frag", (("ALPHA_MASK", 1), ("BATCH", 1))),
    Variant("background_batch.vert.spv", "background.vert", (("BATCH", 1),)),
    Variant("background_batch.frag.spv", "background.frag", (("BATCH", 1),)),
    Variant("batch_cull.comp.spv", "batch_cull.comp", (("STRUCTS_ONLY", 1),)),
    Variant("deform.comp.spv", "deform.comp", (("STRUCTS_ONLY", 1),)),
    Variant("worlds.comp.spv", "worlds.comp"),
    Variant("background.frag.spv", "background.frag"),
    # KHR_materials_transmission's copy of the opaque scene (render/transmission.py): the
    # opaque passes writing linear radiance.
    Variant("pbr_copy_opaque.frag.spv", "pbr.frag", (("ALPHA_MASK", 0), ("OPAQUE_COPY", 1))),
    Variant("pbr_copy_mask.frag.spv", "pbr.frag", (("ALPHA_MASK", 1), ("OPAQUE_COPY", 1))),
    Variant("background_copy.frag.spv", "background.frag", (("OPAQUE_COPY", 1),)),
    # The compute rasteriser (render/compute_path.py).
    *(Variant(f"raster_{name}{'_batch' if batch else ''}.comp.spv", "raster.comp",
              (("COMPUTE_SHADING", 1), ("KERNEL", k), ("BATCH", batch)))
      for k, name in ((1, "small"), (4, "args"), (2, "big"), (3, "resolve"), (5, "masked"),
                      (6, "masked_big"), (7, "clear"))
      for batch in (0, 1) if not batch or k in (1, 2, 5, 6)),
    # Shadow maps drawn by compute shaders (render/shadow_raster.py).
    *(Variant(f"shadow_{name}.comp.spv", "shadow_raster.comp",
              (("COMPUTE_SHADING", 1), ("KERNEL", k)))
      for k, name in ((1, "small"), (3, "args"), (2, "big"), (4, "masked"), (5, "save"),
                      (6, "move"), (7, "clear"))),
)


# Which of `views` an invocation draws through: every shader reads its camera as
# views[view_index]. A single frame has one view; a batch's builds (BATCH) set it first
# thing from their instance (pbr.vert, background.vert), varying (pbr.frag) or tile (the
# compute kernels).
VIEW_INDEX = """#if BATCH
uint view_index;
#else
const uint view_index = 0u;
#endif"""


def generated_glsl() -> str:
    out = _constants()
    out.append("")
    blocks = {b.name: b for b in L.BLOCKS}
    for element in {a.element.name: a.element for a in L.STORAGE.values()
                    if isinstance(a.element, L.Std140Block)}.values():
        struct = element.name + ("Record" if element.name in blocks else "")
        out.append(element.glsl("struct").replace(f"struct {element.name} {{", f"struct {struct} {{")
                   .replace(f"}} {element.instance};", "};"))

    def storage(layout: str, name: str) -> str:
        array = L.STORAGE[name]
        element = array.element
        glsl_type = element if isinstance(element, str) else (
            element.name + ("Record" if element.name in blocks else ""))
        access = "" if name in L.WRITABLE_STORAGE else "readonly "
        decl = (f"{layout}, {array.layout}) {access}buffer {name} {{\n"
                f"    {glsl_type} {array.member}[];\n}};")
        if "64" in glsl_type:  # only the shaders that enable 64-bit integers see it
            decl = f"#if RASTER_INT64  // GL_EXT_shader_explicit_arithmetic_types_int64\n{decl}\n#endif"
        return decl

    # STRUCTS_ONLY: the records without the frame's sets (a kernel with its own bindings,
    # shaders/batch_cull.comp).
    out.append("#if !STRUCTS_ONLY")
    for set_index, rows in L.SETS.items():
        if set_index in L.HAND_DECLARED_SETS:
            continue  # set 3: shaders/shadow_data.glsl + shadow_sampling.glsl
        for binding, kind, _stages, name in rows:
            layout = f"layout(set = {set_index}, binding = {binding}"
            if kind == "uniform":
                # The compute path declares the frame's blocks in its own set (COMPUTE_SET).
                compute_block = any(k == "block" and n == name for _, k, n in L.COMPUTE_SET)
                if compute_block:
                    out.append("#if !COMPUTE_SHADING")
                out.append(blocks[name].glsl(f"{layout}, std140) uniform"))
                if compute_block:
                    out.append("#endif")
            elif kind == "storage":
                out.append(storage(layout, name))
                if name == "Views":
                    out.append(VIEW_INDEX)
            else:
                sampler = "sampler2D" if kind == "sampler" else kind
                out.append(f"{layout}) uniform {sampler} {name};")
    out += _compute_set(storage, blocks)
    out.append("#else  // the compute path has its own push constants")
    out.append(L.PUSH.glsl("layout(push_constant, std430) uniform"))
    out.append("#endif")
    out.append("#endif  // !STRUCTS_ONLY")
    out += ["", "#endif", ""]
    return "\n".join(out)


def _constants() -> list[str]:
    """generated.glsl's opening: the guard, then constants, the sheen fit, enums and flags."""
    out = [
        "// GENERATED by vkpbr.render.codegen from render/layouts.py: do not edit.",
        "#ifndef GENERATED_GLSL",
        "#define GENERATED_GLSL",
        "",
        "#ifndef OPAQUE_COPY  // 1 in the transmission's copy builds (render/transmission.py)",
        "#define OPAQUE_COPY 0",
        "#endif",
        f"const float MIN_ROUGHNESS = {L.MIN_ROUGHNESS!r};",
        f"const float AMBIENT = {L.AMBIENT!r};",
    ]
    out.append(f"const uint MAX_LIGHTS = {L.MAX_LIGHTS}u;")
    out.append(f"const float MIN_SHEEN_ROUGHNESS = {L.MIN_SHEEN_ROUGHNESS!r};")
    out.append(f"const float SHEEN_FIT_MIN_N_DOT_V = {L.SHEEN_FIT_MIN_N_DOT_V!r};")
    out.append(f"const float OPAQUE_COPY_MAX_SIZE = {float(L.OPAQUE_COPY_MAX_SIZE)!r};")
    for field, value in L.LAYER_DEFAULTS.items():  # shade.glsl LAYER_FACTOR (material_table.py)
        v = [repr(float(x)) for x in value]
        out.append(f"const float MATERIAL_DEFAULT_{field} = {v[0]};" if len(v) == 1 else
                   f"const vec{len(v)} MATERIAL_DEFAULT_{field} = vec{len(v)}({', '.join(v)});")
    # KHR_materials_sheen's directional albedo, the polynomial of vkpbr.shading in Horner form
    # (x = cbrt(n.v), y = sqrt(sheen roughness)); literals, no array (lavapipe, see there).
    rows = [" + y * (".join(f"{c!r}" for c in row) + ")" * (len(row) - 1)
            for row in L.SHEEN_ALBEDO_FIT]
    out.append("float sheen_albedo_fit(float x, float y) {")
    out.append("    return " + " + x * (".join(f"({r})" for r in rows) + ")" * (len(rows) - 1) + ";")
    out.append("}")
    enums = ((L.View, "VIEW_"), (L.Brdf, "BRDF_"), (L.Tonemap, "TONEMAP_"), (L.TbnMode, "TBN_"),
             (L.Lighting, "LIGHTING_MODE_"), (L.LightKind, "LIGHT_"))
    for enum_type, prefix in enums:
        out += [f"const int {prefix}{m.name} = {int(m)};" for m in enum_type]
    out += [f"const int VIEW_KIND_{k.name} = {int(k)};" for k in L.ViewKind]
    kinds = ", ".join(str(int(L.VIEW_KIND[v])) for v in L.View)
    out.append(f"const int VIEW_KINDS[{len(L.View)}] = int[]({kinds});")
    for name in dir(L):
        if name.startswith(("SETTINGS_", "MATERIAL_", "LIGHTING_")) and isinstance(getattr(L, name), int):
            out.append(f"const uint {name} = {getattr(L, name)}u;")
    return out


def _compute_set(storage: Callable[[str, str], str], blocks: dict[str, L.Std140Block]
                 ) -> list[str]:
    """The compute path's own set (render/compute_path.py), after the frame's sets."""
    out: list[str] = []
    compute_set = max(L.SETS) + 1
    out.append("#if COMPUTE_SHADING  // the compute path's own set (render/compute_path.py)")
    out.append(f"const uint COMPUTE_SET = {compute_set}u;")
    for binding, kind, name in L.COMPUTE_SET:
        layout = f"layout(set = {compute_set}, binding = {binding}"
        if kind == "storage":
            out.append(storage(layout, name))
        elif kind == "block":
            out.append(blocks[name].glsl(f"{layout}, std140) readonly buffer"))
        else:  # storage_image
            decl = L.STORAGE_IMAGES[name]
            if decl.startswith("layout("):
                fmt, rest = decl[len("layout("):].split(")", 1)
                out.append(f"{layout}, {fmt}){rest} {name};")
            else:
                out.append(f"{layout}) {decl} {name};")
    return out


def glslc() -> str:
    path = shutil.which("glslc")
    if path is None:
        raise ShaderError("glslc not found: install it (apt-get install glslc) to compile shaders")
    return path


def _compile(variant: Variant, out_dir: Path) -> Path:
    dst = out_dir / variant.output
    cmd = [glslc(), "--target-env=vulkan1.3", "-I", str(SHADER_DIR)]
    cmd += [f"-D{k}={val}" for k, val in variant.defines]
    cmd += [str(SHADER_DIR / variant.source), "-o", str(dst)]
    proc = subprocess.run(cmd, capture_output=True, text=True)
    if proc.returncode:
        raise ShaderError(f"glslc failed on {variant.source} {variant.defines}:\n"
                          f"{proc.stderr.strip()}")
    return dst


def compile_all(out_dir: Path = SPV_DIR, write_generated: bool = True) -> list[Path]:
    """Compile every variant into out_dir; returns the written files, in VARIANTS' order.

    No -O: drivers optimise anyway, and unstripped names let tests read block layouts back.
    One glslc process per variant, as many at once as there are cores (each is single-threaded;
    the stale-SPIR-V test runs all ~90 of them).
    """
    if write_generated:
        GENERATED.write_text(generated_glsl())
    out_dir.mkdir(parents=True, exist_ok=True)
    with ThreadPoolExecutor(max_workers=os.cpu_count() or 1) as pool:
        return list(pool.map(lambda v: _compile(v, out_dir), VARIANTS))


if __name__ == "__main__":
    for p in compile_all():
        print(f"wrote {p.relative_to(SHADER_DIR.parent.parent.parent)}")
    sys.exit(0)
