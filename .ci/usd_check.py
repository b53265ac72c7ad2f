"""Checks PGE's USD exports with usd-core: the UsdValidation validators (what usdchecker
runs) report no error, and the mesh prims, points and instances equal the glb's.

usage: .ci/usd_check.py FILE.usda|FILE.usdz [FILE.glb]
"""

import json
import struct
import sys

from pxr import Usd, UsdGeom, UsdValidation


def validate(stage):
    reg = UsdValidation.ValidationRegistry()
    ctx = UsdValidation.ValidationContext(reg.GetOrLoadAllValidators())
    errors = [e for e in ctx.Validate(stage)
              if e.GetType() == UsdValidation.ValidationErrorType.Error]
    warnings = [e for e in ctx.Validate(stage)
                if e.GetType() == UsdValidation.ValidationErrorType.Warn]
    return errors, warnings


def usd_counts(stage):
    """Mesh prims, their points and the point instancers' instances (each prototype once);
    problems: a prototype that is not a prim under its instancer, an index out of range,
    arrays of unequal lengths."""
    meshes = points = instances = 0
    problems = []
    for prim in stage.Traverse():
        if prim.IsA(UsdGeom.Mesh):
            meshes += 1
            points += len(UsdGeom.Mesh(prim).GetPointsAttr().Get() or [])
        elif prim.IsA(UsdGeom.PointInstancer):
            pi = UsdGeom.PointInstancer(prim)
            indices = pi.GetProtoIndicesAttr().Get() or []
            instances += len(indices)
            targets = pi.GetPrototypesRel().GetTargets()
            for t in targets:
                if not stage.GetPrimAtPath(t) or not t.HasPrefix(prim.GetPath()):
                    problems.append(f"{prim.GetPath()}: prototype {t} is not a prim under it")
            if indices and max(indices) >= len(targets):
                problems.append(f"{prim.GetPath()}: a proto index beyond its prototypes")
            lengths = {len(a.Get() or []) for a in (pi.GetPositionsAttr(),
                       pi.GetOrientationsAttr(), pi.GetScalesAttr())} | {len(indices)}
            if len(lengths) != 1:
                problems.append(f"{prim.GetPath()}: arrays of lengths {sorted(lengths)}")
    return (meshes, points, instances), problems


def glb_counts(path):
    """Triangle primitives of the nodes' meshes, their vertices, and the instances (a node
    with EXT_mesh_gpu_instancing counts its placements, its mesh once)."""
    data = open(path, "rb").read()
    length = struct.unpack_from("<I", data, 12)[0]
    gltf = json.loads(data[20:20 + length])
    nodes = gltf.get("nodes", [])
    scene = gltf["scenes"][gltf.get("scene", 0)]
    meshes = points = instances = 0
    stack = list(scene["nodes"])
    while stack:
        node = nodes[stack.pop()]
        stack.extend(node.get("children", []))
        if "mesh" not in node:
            continue
        for p in gltf["meshes"][node["mesh"]]["primitives"]:
            if p.get("mode", 4) == 4:
                meshes += 1
                points += gltf["accessors"][p["attributes"]["POSITION"]]["count"]
        ext = node.get("extensions", {}).get("EXT_mesh_gpu_instancing")
        if ext:
            instances += gltf["accessors"][ext["attributes"]["TRANSLATION"]]["count"]
    return meshes, points, instances


def main():
    usd = sys.argv[1]
    stage = Usd.Stage.Open(usd)
    if stage is None:
        sys.exit(f"{usd}: USD cannot open it")
    errors, warnings = validate(stage)
    for e in errors:
        print(f"{usd}: error: {e.GetMessage()}")
    for w in warnings:
        print(f"{usd}: warning: {w.GetMessage()}")
    counts, problems = usd_counts(stage)
    for p in problems:
        print(f"{usd}: error: {p}")
    print(f"{usd}: {len(errors)} errors, {len(warnings)} warnings; "
          f"meshes {counts[0]}, points {counts[1]}, instances {counts[2]}")
    failed = bool(errors or problems)
    if len(sys.argv) > 2:
        want = glb_counts(sys.argv[2])
        if counts != want:
            print(f"{usd}: counts {counts} differ from {sys.argv[2]}'s {want}")
            failed = True
    sys.exit(1 if failed else 0)


if __name__ == "__main__":
    main()
