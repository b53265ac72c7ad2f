//! Wavefront `.obj` + `.mtl` export (for tools without glTF).

use crate::math;
use std::fmt::Write;

use crate::geometry::{Model, Primitive};
use crate::{Error, Result};

/// The files of an OBJ export: the `.obj` text, the `.mtl` text and the PNG textures it
/// refers to (file name, bytes).
#[derive(Clone, Debug, Default)]
pub struct ObjFiles {
    /// The geometry.
    pub obj: String,
    /// The materials.
    pub mtl: String,
    /// Texture files next to them.
    pub textures: Vec<(String, Vec<u8>)>,
}

fn srgb(c: f32) -> f32 {
    if c <= 0.0031308 {
        c * 12.92
    } else {
        1.055 * math::powf(c, 1.0 / 2.4) - 0.055
    }
}

/// Writes every instance of the model with its transform applied; `mtl_name` is the file
/// name the `.obj` refers to, `stem` prefixes texture file names.
pub fn obj_files(model: &Model, mtl_name: &str, stem: &str) -> Result<ObjFiles> {
    obj_files_checked(model, mtl_name, stem, &mut |_| Ok(()))
}

/// Vertices written between two calls of [`obj_files_checked`]'s `check`.
const CHECK_EVERY: usize = 1 << 16;

/// [`obj_files`], calling `check` with the bytes of `.obj` text written so far before the
/// first instance and then every [`CHECK_EVERY`] vertices or so (an instance is written
/// whole): its error (a run's deadline, [`crate::RunContext::check_deadline`], or its memory
/// budget, [`crate::Budget::check`], which the text must fit) stops the export. A forest's
/// every placement is written out, so the text grows with the trees times their vertices.
pub fn obj_files_checked(
    model: &Model,
    mtl_name: &str,
    stem: &str,
    check: &mut dyn FnMut(usize) -> Result<()>,
) -> Result<ObjFiles> {
    check(0)?;
    model.validate()?;
    let mut out = ObjFiles::default();
    let e = |err: std::fmt::Error| Error::Export(err.to_string());
    writeln!(out.obj, "# {}\nmtllib {mtl_name}", super::glb::GENERATOR).map_err(e)?;
    let mut materials: Vec<std::sync::Arc<crate::geometry::Material>> = Vec::new();
    let (mut v_base, mut vt_base, mut vn_base) = (1usize, 1usize, 1usize);
    // Groups (forests) have no instancing in OBJ: every placement is written out.
    let grouped = model.groups.iter().flat_map(|g| {
        g.transforms.iter().flat_map(move |t| {
            let m = t.matrix();
            g.meshes
                .iter()
                .map(move |&mesh| crate::geometry::Instance { mesh, transform: m })
        })
    });
    let all: Vec<crate::geometry::Instance> =
        model.instances.iter().cloned().chain(grouped).collect();
    let mut unchecked = 0;
    for (n, inst) in all.iter().enumerate() {
        let mesh = &model.meshes[inst.mesh];
        unchecked += mesh.positions.len() + 1;
        if unchecked >= CHECK_EVERY {
            check(out.obj.len())?;
            unchecked = 0;
        }
        let mi = match materials.iter().position(|m| **m == *mesh.material) {
            Some(i) => i,
            None => {
                materials.push(mesh.material.clone());
                materials.len() - 1
            }
        };
        let normal_matrix = inst.transform.inverse().transpose();
        writeln!(
            out.obj,
            "o {}_{n}\nusemtl m{mi}",
            mesh.name.replace(char::is_whitespace, "_")
        )
        .map_err(e)?;
        for p in &mesh.positions {
            let p = inst.transform.transform_point3(*p);
            writeln!(out.obj, "v {} {} {}", p.x, p.y, p.z).map_err(e)?;
        }
        for t in &mesh.uvs {
            writeln!(out.obj, "vt {} {}", t.x, 1.0 - t.y).map_err(e)?;
        }
        for nrm in &mesh.normals {
            let v = normal_matrix.transform_vector3(*nrm).normalize_or_zero();
            writeln!(out.obj, "vn {} {} {}", v.x, v.y, v.z).map_err(e)?;
        }
        let corner = |i: u32| {
            let i = i as usize;
            match (mesh.uvs.is_empty(), mesh.normals.is_empty()) {
                (true, true) => format!("{}", v_base + i),
                (false, true) => format!("{}/{}", v_base + i, vt_base + i),
                (true, false) => format!("{}//{}", v_base + i, vn_base + i),
                (false, false) => format!("{}/{}/{}", v_base + i, vt_base + i, vn_base + i),
            }
        };
        match mesh.primitive {
            Primitive::Triangles => {
                for t in mesh.indices.chunks_exact(3) {
                    writeln!(
                        out.obj,
                        "f {} {} {}",
                        corner(t[0]),
                        corner(t[1]),
                        corner(t[2])
                    )
                    .map_err(e)?;
                }
            }
            Primitive::Lines => {
                for l in mesh.indices.chunks_exact(2) {
                    writeln!(
                        out.obj,
                        "l {} {}",
                        v_base + l[0] as usize,
                        v_base + l[1] as usize
                    )
                    .map_err(e)?;
                }
            }
        }
        v_base += mesh.positions.len();
        vt_base += mesh.uvs.len();
        vn_base += mesh.normals.len();
    }
    for (i, m) in materials.iter().enumerate() {
        let [r, g, b, a] = m.base_color;
        writeln!(
            out.mtl,
            "newmtl m{i}\n# {}\nKd {} {} {}\nd {a}",
            m.name,
            srgb(r),
            srgb(g),
            srgb(b)
        )
        .map_err(e)?;
        if let Some(t) = &m.texture {
            let file = format!("{stem}_{i}.{}", t.extension());
            writeln!(out.mtl, "map_Kd {file}").map_err(e)?;
            if !matches!(m.alpha, crate::geometry::AlphaMode::Opaque) {
                writeln!(out.mtl, "map_d {file}").map_err(e)?;
            }
            out.textures.push((file, t.encoded.clone()));
        }
    }
    Ok(out)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::geometry::Mesh;
    use glam::{Mat4, Vec3};

    #[test]
    fn obj_has_one_face_per_triangle_per_instance() {
        let mesh =
            Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
        let mut model = Model::from_mesh(mesh);
        let copy = model.meshes[0].clone();
        model.add_mesh(copy, Mat4::from_translation(Vec3::Z));
        let files = obj_files(&model, "a.mtl", "a").expect("exports");
        assert_eq!(files.obj.lines().filter(|l| l.starts_with("f ")).count(), 2);
        assert_eq!(files.obj.lines().filter(|l| l.starts_with("v ")).count(), 6);
        assert!(files.obj.contains("f 4//4 5//5 6//6"));
        assert!(files.mtl.starts_with("newmtl m0"));
    }
}
