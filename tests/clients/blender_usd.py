"""Imports a USD forest with Blender's USD importer (bpy) and checks it arrived instanced.

    python blender_usd.py FILE.usdz MESHES INSTANCES

In a fresh Blender scene: the import succeeds; Blender has MESHES meshes (each prototype's
meshes once, not one copy per tree); every point instancer became a point cloud whose
Geometry Nodes modifier instances the prototypes, and the point clouds hold INSTANCES
points in all (one per tree). Exits 1 when the file fails, printing why.
"""

import sys

import bpy


def main():
    path, meshes, instances = sys.argv[1], int(sys.argv[2]), int(sys.argv[3])
    bpy.ops.wm.read_factory_settings(use_empty=True)
    result = bpy.ops.wm.usd_import(filepath=path)
    problems = []
    if result != {"FINISHED"}:
        problems.append(f"the import returned {result}")
    if len(bpy.data.meshes) != meshes:
        problems.append(f"{len(bpy.data.meshes)} meshes, expected {meshes}")
    clouds = [o for o in bpy.data.objects if o.type == "POINTCLOUD"]
    for o in clouds:
        if not any(m.type == "NODES" for m in o.modifiers):
            problems.append(f"{o.name}: a point cloud without its instancing modifier")
    points = sum(len(o.data.points) for o in clouds)
    if points != instances:
        problems.append(f"{points} instanced points, expected {instances}")
    for p in problems:
        print(f"{path}: blender: {p}")
    print(f"{path}: blender imported {len(bpy.data.meshes)} meshes, "
          f"{len(clouds)} instancers of {points} instances")
    sys.exit(1 if problems else 0)


if __name__ == "__main__":
    main()
