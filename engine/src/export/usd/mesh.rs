//! A mesh prim's text: its arrays, primvars and material binding, and the customData of
//! its skeleton and levels of detail.

use super::*;

/// The text of a mesh prim.
pub(super) fn mesh_text(job: &MeshJob) -> String {
    let MeshJob {
        mesh,
        name,
        transform,
        material,
        depth,
    } = job;
    let mesh: &Mesh = mesh;
    let bytes = 16 * 3 * (mesh.positions.len() + mesh.normals.len()) + 8 * mesh.indices.len();
    let mut text = Text::with_capacity(bytes + 1024);
    text.set_depth(*depth);
    let t = &mut text;
    let kind = match mesh.primitive {
        Primitive::Triangles => "Mesh",
        Primitive::Lines => "BasisCurves",
    };
    t.open(&format!("def {kind} \"{name}\""), "(");
    t.put("prepend apiSchemas = [\"MaterialBindingAPI\"]");
    let has_data = mesh.skeleton.is_some() || mesh.lod.is_some() || !mesh.extras.is_empty();
    if has_data {
        t.line().push_str("customData = {");
        t.depth_in();
        t.line().push_str("dictionary pge = {");
        t.depth_in();
        if let Some(sk) = &mesh.skeleton {
            skeleton(t, sk);
        }
        if let Some(lod) = &mesh.lod {
            t.line().push_str("dictionary lod = {");
            t.depth_in();
            lod_entries(t, lod);
            t.close("}");
        }
        t.json_entries(&mesh.extras);
        t.close("}");
        t.close("}");
    }
    t.close(")");
    t.open("", "{");
    if mesh.material.double_sided {
        t.put("uniform bool doubleSided = 1");
    }
    if let Some((lo, hi)) = mesh.bounds() {
        t.line().push_str("float3[] extent = [");
        t.tuple(&lo.to_array());
        t.out.push_str(", ");
        t.tuple(&hi.to_array());
        t.out.push(']');
    }
    match mesh.primitive {
        Primitive::Triangles => {
            t.line().push_str("int[] faceVertexCounts = [");
            for k in 0..mesh.indices.len() / 3 {
                t.out.push_str(if k > 0 { ", 3" } else { "3" });
            }
            t.out.push(']');
            t.line().push_str("int[] faceVertexIndices = ");
            t.array(&mesh.indices, |t, &i| t.int(i));
            t.put(&format!("rel material:binding = <{material}>"));
            if !mesh.normals.is_empty() {
                t.line().push_str("normal3f[] normals = ");
                t.array(&mesh.normals, |t, n| t.tuple(&n.to_array()));
                t.out.push_str(" (");
                t.depth_in();
                t.put("interpolation = \"vertex\"");
                t.close(")");
            }
            t.line().push_str("point3f[] points = ");
            t.array(&mesh.positions, |t, p| t.tuple(&p.to_array()));
        }
        Primitive::Lines => {
            t.line().push_str("int[] curveVertexCounts = [");
            for k in 0..mesh.indices.len() / 2 {
                t.out.push_str(if k > 0 { ", 2" } else { "2" });
            }
            t.out.push(']');
            t.put(&format!("rel material:binding = <{material}>"));
            t.line().push_str("point3f[] points = ");
            t.array(&mesh.indices, |t, &i| {
                t.tuple(&mesh.positions[i as usize].to_array());
            });
            t.put("uniform token type = \"linear\"");
        }
    }
    if !mesh.colors.is_empty() {
        let corners = |t: &mut Text, f: &dyn Fn(&mut Text, usize)| match mesh.primitive {
            Primitive::Triangles => {
                t.out.push('[');
                for k in 0..mesh.colors.len() {
                    if k > 0 {
                        t.out.push_str(", ");
                    }
                    f(t, k);
                }
                t.out.push(']');
            }
            Primitive::Lines => t.array(&mesh.indices, |t, &i| f(t, i as usize)),
        };
        t.line().push_str("color3f[] primvars:displayColor = ");
        corners(t, &|t, k| t.tuple(&mesh.colors[k].truncate().to_array()));
        t.out.push_str(" (");
        t.depth_in();
        t.put("interpolation = \"vertex\"");
        t.close(")");
        t.line().push_str("float[] primvars:displayOpacity = ");
        corners(t, &|t, k| t.float(mesh.colors[k].w));
        t.out.push_str(" (");
        t.depth_in();
        t.put("interpolation = \"vertex\"");
        t.close(")");
    }
    if !mesh.uvs.is_empty() && mesh.primitive == Primitive::Triangles {
        // glTF's v runs down the image, USD's t up.
        t.line().push_str("texCoord2f[] primvars:st = ");
        t.array(&mesh.uvs, |t, uv| t.tuple(&[uv.x, 1.0 - uv.y]));
        t.out.push_str(" (");
        t.depth_in();
        t.put("interpolation = \"vertex\"");
        t.close(")");
    }
    if mesh.primitive == Primitive::Triangles {
        t.put("uniform token subdivisionScheme = \"none\"");
    }
    if let Some(m) = transform.filter(|m| *m != Mat4::IDENTITY) {
        t.line().push_str("matrix4d xformOp:transform = (");
        for (k, col) in m.to_cols_array_2d().iter().enumerate() {
            if k > 0 {
                t.out.push_str(", ");
            }
            // USD's matrices are row-major with the translation in the last row: the
            // rows are glam's columns.
            t.tuple(col);
        }
        t.out.push(')');
        t.put("uniform token[] xformOpOrder = [\"xformOp:transform\"]");
    }
    t.close("}");
    text.out
}

/// A skeleton as `dictionary skeleton = {parents, positions, radii, orders}`, the arrays of
/// the glb's `extras.pge.skeleton` (a root's parent is -1).
fn skeleton(t: &mut Text, sk: &Skeleton) {
    t.line().push_str("dictionary skeleton = {");
    t.depth_in();
    t.line().push_str("int[] parents = ");
    t.array(&sk.parents, |t, p| t.int(p.map_or(-1, i64::from)));
    t.line().push_str("float3[] positions = ");
    t.array(&sk.positions, |t, p| t.tuple(&p.to_array()));
    t.line().push_str("float[] radii = ");
    t.array(&sk.radii, |t, &r| t.float(r));
    t.line().push_str("int[] orders = ");
    t.array(&sk.orders, |t, &o| t.int(o));
    t.close("}");
}

/// The levels of detail as the glb's `extras.pge.lod`: `leaves`, `roots` and `table` (rows
/// `(a, b, c)`), or `sectors` (a dictionary `"0"`, `"1"`, ... of `offset, leaves, roots,
/// table`); a group's `primitives` likewise.
fn lod_entries(t: &mut Text, lod: &MeshLod) {
    let table_entries = |t: &mut Text, table: &crate::geometry::LodTable| {
        t.json_entry("leaves", &json!(table.leaves()));
        t.json_entry("roots", &json!(table.roots()));
        let rows = |t: &mut Text, levels: &[crate::geometry::LodLevel]| {
            t.line().push_str("int64[] \"table\" = [");
            for (k, l) in levels.iter().enumerate() {
                if k > 0 {
                    t.out.push_str(", ");
                }
                t.int(l.a);
                t.out.push_str(", ");
                t.int(l.b);
                t.out.push_str(", ");
                t.int(l.c);
            }
            t.out.push(']');
        };
        match table.sectors() {
            [one] => rows(t, one.levels()),
            sectors => {
                t.line().push_str("dictionary \"sectors\" = {");
                t.depth_in();
                for (k, s) in sectors.iter().enumerate() {
                    t.line().push_str(&format!("dictionary \"{k}\" = {{"));
                    t.depth_in();
                    t.json_entry("offset", &json!(s.offset()));
                    t.json_entry("leaves", &json!(s.leaves()));
                    t.json_entry("roots", &json!(s.roots()));
                    rows(t, s.levels());
                    t.close("}");
                }
                t.close("}");
            }
        }
    };
    match lod {
        MeshLod::Leaves(table) => table_entries(t, table),
        MeshLod::Group(group) => {
            t.json_entry("leaves", &json!(lod.leaves()));
            t.json_entry("roots", &json!(lod.roots()));
            t.line().push_str("dictionary \"primitives\" = {");
            t.depth_in();
            for (k, p) in group.primitives().iter().enumerate() {
                t.line().push_str(&format!("dictionary \"{k}\" = {{"));
                t.depth_in();
                t.json_entry("primitive", &json!(p.primitive));
                table_entries(t, &p.table);
                t.close("}");
            }
            t.close("}");
        }
    }
}
