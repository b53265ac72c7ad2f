"""What pge-world reads in a .glb: its JSON chunk and the root ``extras.pge``."""

from __future__ import annotations

import json
import struct
from typing import Any

from .errors import WorldError


def json_chunk(data: bytes) -> dict[str, Any]:
    """Return the JSON chunk of a .glb, as a dictionary."""
    if len(data) < 20 or data[:4] != b"glTF":
        raise WorldError("not a .glb file")
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        raise WorldError("a .glb without a JSON chunk")
    document = json.loads(data[20 : 20 + length])
    if not isinstance(document, dict):
        raise WorldError("a .glb whose JSON chunk is not an object")
    return document


def root_extras(data: bytes) -> dict[str, Any]:
    """Return the root ``extras.pge`` of a .glb's JSON chunk (an empty dict when it has none)."""
    extras: dict[str, Any] = (json_chunk(data).get("extras") or {}).get("pge") or {}
    return extras


def buffer_uris(data: bytes) -> list[str]:
    """Return the URIs of a .glb's buffers that name a file (none for the .glb's own chunk)."""
    buffers = json_chunk(data).get("buffers") or []
    return [b["uri"] for b in buffers if isinstance(b.get("uri"), str)]
