"""Imports glb files with Blender's glTF importer (bpy) and checks what Blender built.

    python blender.py FILE.glb...

For each file, in a fresh Blender scene: the import succeeds; Blender has one mesh per glTF
mesh and the glTF's materials; one mesh object per placement (a node with a mesh, or each
instance of an EXT_mesh_gpu_instancing node); the run's `extras.pge` (generator, seed,
params, stats) on the Blender scene; and every glTF mesh's `extras.pge` (skeletons, LOD
tables) on its Blender mesh. What is expected is read from the file's own JSON chunk, so the
test follows the scripts. Exits 1 when a file fails, printing why.
"""

import json
import struct
import sys

import bpy


def gltf_json(path):
    """The JSON chunk of a glb file."""
    with open(path, "rb") as f:
        data = f.read()
    magic, _version, _length = struct.unpack_from("<4sII", data, 0)
    if magic != b"glTF":
        raise ValueError(f"{path}: not a glb file")
    length, kind = struct.unpack_from("<I4s", data, 12)
    if kind != b"JSON":
        raise ValueError(f"{path}: the first chunk is not JSON")
    return json.loads(data[20 : 20 + length])


def expected(doc):
    """What Blender should build from the glTF document `doc`.

    Blender imports every scene of the file (a `--stages` glb has one per stage), so the
    placements are counted over the nodes of all scenes, each node once.
    """
    nodes = doc.get("nodes", [])
    accessors = doc.get("accessors", [])
    placements = 0
    seen = set()
    stack = [n for scene in doc.get("scenes", []) for n in scene.get("nodes", [])]
    while stack:
        index = stack.pop()
        if index in seen:
            continue
        seen.add(index)
        node = nodes[index]
        stack.extend(node.get("children", []))
        if "mesh" not in node:
            continue
        gpu = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
        if gpu:
            placements += accessors[gpu["attributes"]["TRANSLATION"]]["count"]
        else:
            placements += 1
    meshes = doc.get("meshes", [])
    return {
        "meshes": len(meshes),
        "materials": len(doc.get("materials", [])),
        "objects": placements,
        "mesh_extras": sorted(m["name"] for m in meshes if "pge" in m.get("extras", {})),
        "scenes": max(len(doc.get("scenes", [])), 1),
    }


def to_python(value):
    """A Blender ID property (or plain value) as plain Python data."""
    if hasattr(value, "to_dict"):
        return value.to_dict()
    if hasattr(value, "to_list"):
        return value.to_list()
    return value


def imported(path):
    """Imports `path` into an empty scene and counts what Blender made."""
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.import_scene.gltf(filepath=path)
    if result != {"FINISHED"}:
        raise RuntimeError(f"the importer returned {result}")
    # The scene that holds the run's extras is the file's default scene, the one the importer
    # makes active; objects are counted over every scene it made.
    scene = bpy.context.scene
    mesh_objects = [o for o in bpy.data.objects if o.type == "MESH" and o.users_scene]
    used_meshes = {o.data.name: o.data for o in mesh_objects}
    return {
        "meshes": len(bpy.data.meshes),
        "materials": len(bpy.data.materials),
        "objects": len(mesh_objects),
        "mesh_extras": sorted(
            m.name.split(".")[0] for m in used_meshes.values() if "pge" in m.keys()
        ),
        "scene_extras": to_python(scene["pge"]) if "pge" in scene.keys() else None,
        "faces": sum(len(o.data.polygons) for o in mesh_objects),
        "edges": sum(len(o.data.edges) for o in mesh_objects),
        "scenes": len(bpy.data.scenes),
    }


def check(path):
    """The problems found importing `path` (empty when Blender built what the file says)."""
    doc = gltf_json(path)
    want = expected(doc)
    got = imported(path)
    problems = []
    for key in ("meshes", "materials", "objects", "scenes"):
        if got[key] != want[key]:
            problems.append(f"{key}: Blender has {got[key]}, the file has {want[key]}")
    # Blender names meshes after the glTF mesh; names may repeat, so compare the sets.
    if sorted(set(got["mesh_extras"])) != sorted(set(want["mesh_extras"])):
        problems.append(
            f"meshes with extras.pge: Blender {got['mesh_extras']}, file {want['mesh_extras']}"
        )
    extras = got["scene_extras"]
    root = doc.get("extras", {}).get("pge", {})
    if extras is None:
        problems.append("the scene has no extras.pge (Blender drops the root's)")
    else:
        for key in ("generator", "seed", "params", "stats"):
            if key not in extras:
                problems.append(f"the scene's extras.pge has no {key}")
        if extras.get("generator") != root.get("generator"):
            problems.append("the scene's generator differs from the root's")
        if extras.get("stats", {}).get("triangles") != root.get("stats", {}).get("triangles"):
            problems.append("the scene's stats differ from the root's")
    if got["faces"] == 0 and got["edges"] == 0:
        problems.append("nothing imported: no face and no edge")
    return want, got, problems


def main(paths):
    failures = 0
    for path in paths:
        try:
            want, got, problems = check(path)
        except Exception as e:  # noqa: BLE001 - any importer failure fails the file
            failures += 1
            print(f"FAIL {path}: {type(e).__name__}: {e}")
            continue
        if problems:
            failures += 1
            print(f"FAIL {path}: " + "; ".join(problems))
        else:
            print(
                f"ok   {path}: {got['meshes']} meshes, {got['materials']} materials, "
                f"{got['objects']} objects in {got['scenes']} scenes, {got['faces']} faces, "
                f"{len(want['mesh_extras'])} meshes with extras, scene extras "
                f"{sorted(got['scene_extras'])}"
            )
    if failures:
        print(f"blender: {failures} of {len(paths)} files failed")
        return 1
    print(f"blender {bpy.app.version_string}: all {len(paths)} files import")
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
