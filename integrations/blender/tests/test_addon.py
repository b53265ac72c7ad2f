"""The PGE add-on in headless Blender (the bpy module), from the repository root.

    python integrations/blender/tests/test_addon.py      (or pytest)

Registers the add-on, generates the oak (objects, meshes, materials and images as its glb
has them), changes a parameter (a different mesh, the result's transform kept), fails a
script (the error as FILE:LINE: message, the previous result kept), regenerates live when
the script is saved, grows the mixed forest (linked duplicates: one mesh per variant, as many
objects as the forest's instances) and unregisters. `.ci/blender` runs it.
"""

from __future__ import annotations

import json
import os
import struct
import sys
import tempfile
import time
from pathlib import Path

import bpy

ROOT = Path(__file__).resolve().parents[3]
sys.path.insert(0, str(ROOT / "integrations" / "blender"))

import pge  # noqa: E402
import pge_blender  # noqa: E402


def glb_json(glb: bytes) -> dict:
    length, kind = struct.unpack_from("<I4s", glb, 12)
    assert kind == b"JSON"
    return json.loads(glb[20 : 20 + length])


def result_objects(root) -> list:
    return [o for o in root.children_recursive if o.type == "MESH"]


def counts(root) -> dict:
    objects = result_objects(root)
    meshes = {o.data for o in objects}
    materials = {m for mesh in meshes for m in mesh.materials if m}
    images = {
        n.image
        for m in materials
        if m.node_tree
        for n in m.node_tree.nodes
        if getattr(n, "image", None)
    }
    return {
        "objects": len(objects),
        "meshes": len(meshes),
        "materials": len(materials),
        "images": len(images),
    }


def generate() -> set:
    return bpy.ops.pge.generate()


def test_the_addon_end_to_end() -> None:
    bpy.ops.wm.read_factory_settings(use_empty=True)
    pge_blender.register()
    try:
        scenario()
    finally:
        pge_blender.unregister()
    assert not hasattr(bpy.types.Scene, "pge")
    assert not hasattr(bpy.ops.pge, "generate") or "generate" not in dir(bpy.ops.pge)


def scenario() -> None:
    scene = bpy.context.scene
    settings = scene.pge
    assert pge_blender.backend() == "module"

    # The oak: the parameters as properties, what the glb holds as objects and data.
    oak = str(ROOT / "scripts" / "species" / "oak.lua")
    settings.script = oak
    height = pge_blender._params_class.__annotations__["height"]
    assert height.keywords["min"] == 1.0 and height.keywords["max"] == 20.0
    assert height.keywords["description"] == "crown half-height (m)"
    assert generate() == {"FINISHED"}
    root = settings.target
    assert root is not None and root.name == "oak"
    assert root.users_collection[0].name == "PGE"
    doc = glb_json(pge.generate(oak).glb)
    want = {
        "objects": len(doc["nodes"]) - sum(1 for n in doc["nodes"] if "mesh" not in n),
        "meshes": len(doc["meshes"]),
        "materials": len(doc["materials"]),
        "images": len(doc["images"]),
    }
    got = counts(root)
    assert got == want, (got, want)
    assert want["images"] > 0 and want["materials"] > 0
    first = [tuple(v.co) for v in result_objects(root)[0].data.vertices[:50]]
    meshes_before = len(bpy.data.meshes)

    # A property changes: a different mesh; the result's transform stays; nothing piles up.
    root.location = (5.0, 2.0, 0.0)
    scene.pge_params.height = 6.0
    assert generate() == {"FINISHED"}
    assert settings.target == root
    assert tuple(root.location) == (5.0, 2.0, 0.0)
    assert counts(root) == want
    changed = [tuple(v.co) for v in result_objects(root)[0].data.vertices[:50]]
    assert changed != first
    assert len(bpy.data.meshes) == meshes_before

    # A failing script: the error with file and line; the previous result stays.
    with tempfile.TemporaryDirectory() as tmp:
        bad = Path(tmp) / "bad.lua"
        bad.write_text("local x = 1\nlocal y = nil + x\nreturn y\n")
        settings.script = str(bad)
        try:
            result = generate()
        except RuntimeError as e:  # bpy.ops raises the operator's error report
            result = {"CANCELLED"}
            assert f"{bad}:2:" in str(e), e
        assert result == {"CANCELLED"}
        assert settings.error.startswith(f"{bad}:2: "), settings.error
        assert counts(root) == want
        assert tuple(root.location) == (5.0, 2.0, 0.0)

        # Live: saving the script regenerates it (the timer's tick, called as Blender would).
        koch = (ROOT / "scripts" / "lsystems" / "koch.lua").read_text()
        bad.write_text(koch)
        settings.live = True
        time.sleep(0.01)
        assert pge_blender.watch() == pge_blender.WATCH_INTERVAL
        assert settings.error == "", settings.error
        live = counts(root)
        assert live["objects"] >= 1 and live != want

        def vertices() -> int:
            return sum(len(o.data.vertices) for o in result_objects(root))

        # Saved again: the watcher sees the file's new time and regenerates.
        island = vertices()
        bad.write_text(koch.replace('variant = {"island"', 'variant = {"snowflake"'))
        later = time.time() + 5
        os.utime(bad, (later, later))
        pge_blender.watch()
        snowflake = vertices()
        assert snowflake != island
        # A property change waits for the debounce, then regenerates once.
        settings.steps = 2
        pge_blender.watch()
        assert vertices() == snowflake
        time.sleep(pge_blender.DEBOUNCE + 0.05)
        pge_blender.watch()
        assert vertices() < snowflake
        live = counts(root)
        settings.live = False
        assert pge_blender.watch() is None
        settings.steps = 0

    # The mixed forest: linked duplicates, one object per instance, one mesh per variant.
    settings.target = None
    settings.script = str(ROOT / "scripts" / "forests" / "mixed.lua")
    scene.pge_params.size = 60
    scene.pge_params.variants = 1
    scene.pge_params.points = 200
    forest = pge.generate(
        settings.script, params={"size": 60, "variants": 1, "points": 200}
    )
    assert generate() == {"FINISHED"}
    trees = settings.target
    assert trees != root and trees.name == "mixed"
    objects = result_objects(trees)
    shared = [o for o in objects if o.data.users > 1]
    assert len(shared) == forest.stats["instances"], (len(shared), forest.stats["instances"])
    meshes = {o.data for o in objects}
    assert len(meshes) == len(glb_json(forest.glb)["meshes"])
    # The earlier result is still there.
    assert counts(root) == live


if __name__ == "__main__":
    test_the_addon_end_to_end()
    print(f"blender {bpy.app.version_string}: the PGE add-on works")
