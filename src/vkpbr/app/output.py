"""The CLI's output files under their first import path: the writers and checks are
`vkpbr.io`'s (library code, used by vkpbr.distributed and vkpbr.show as well as the CLI);
`vkpbr.app.output.write_output`, which earlier READMEs named, keeps working through here.
"""

from __future__ import annotations

from vkpbr.io import (
    FORMATS,
    IMAGE_SUFFIXES,
    MAX_PNG_ID,
    OUTPUT_KINDS,
    OUTPUT_SUFFIXES,
    Kind,
    check_id_count,
    check_output_path,
    check_outputs,
    check_writable,
    encode_png,
    output_kind,
    output_path,
    write_image,
    write_image_atomic,
    write_output,
    write_outputs,
)

__all__ = [
    "FORMATS",
    "IMAGE_SUFFIXES",
    "MAX_PNG_ID",
    "OUTPUT_KINDS",
    "OUTPUT_SUFFIXES",
    "Kind",
    "check_id_count",
    "check_output_path",
    "check_outputs",
    "check_writable",
    "encode_png",
    "output_kind",
    "output_path",
    "write_image",
    "write_image_atomic",
    "write_output",
    "write_outputs",
]
