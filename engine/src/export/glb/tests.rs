//! Tests of the glb writer: meshes, materials, extras, instancing.

use super::layout::{BOUNDS_PIECE, vec3_bounds};
use super::*;
use crate::geometry::{AlphaMode, InstanceGroup, Texture};
use crate::geometry::{Material, Mesh, Skeleton};
use crate::math;
use glam::{Mat4, Quat, Vec2, Vec3};

pub(super) fn textured_model() -> Model {
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
    let tex = Texture::from_rgba("leaf", 2, 2, &[255; 16]).expect("png");
    mesh.material = Arc::new(Material {
        texture: Some(Arc::new(tex)),
        alpha: AlphaMode::Mask(0.5),
        double_sided: true,
        ..Material::default()
    });
    let mut s = Skeleton::new();
    let r = s.push(Vec3::ZERO, None, 0.1, 0);
    s.push(Vec3::Y, Some(r), 0.05, 0);
    mesh.skeleton = Some(Arc::new(s));
    let mesh = Arc::new(mesh);
    let mut model = Model::new();
    model.add_mesh(mesh.clone(), Mat4::IDENTITY);
    model.add_mesh(
        mesh,
        Mat4::from_rotation_translation(Quat::from_rotation_y(1.0), Vec3::X),
    );
    model
}

#[test]
fn normal_and_roughness_maps_are_written_once_each() {
    let mut model = textured_model();
    let png = |name: &str| Arc::new(Texture::from_rgba(name, 2, 2, &[128; 16]).expect("png"));
    let (normal, rough) = (png("bark normal"), png("bark roughness"));
    let mut mesh = (*model.meshes[0]).clone();
    mesh.material = Arc::new(Material {
        normal_texture: Some(normal),
        metallic_roughness_texture: Some(rough),
        ..(*mesh.material).clone()
    });
    model.meshes[0] = Arc::new(mesh);
    let bytes = glb_bytes(&model, &ExportMeta::default()).expect("exports");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
    assert_eq!(gltf.images().count(), 3);
    let m = gltf.materials().next().expect("material");
    let n = m.normal_texture().expect("normal texture");
    assert_eq!(n.texture().source().name(), Some("bark normal"));
    assert_eq!(n.scale(), 1.0);
    let mr = m
        .pbr_metallic_roughness()
        .metallic_roughness_texture()
        .expect("metallic-roughness texture");
    assert_eq!(mr.texture().source().name(), Some("bark roughness"));
}

#[test]
fn glb_parses_back_with_the_gltf_crate() {
    let model = textured_model();
    let bytes = glb_bytes(
        &model,
        &ExportMeta {
            seed: 7,
            params: vec![("h".into(), json!(2))],
        },
    )
    .expect("exports");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
    assert_eq!(gltf.meshes().count(), 1);
    assert_eq!(gltf.nodes().count(), 2);
    assert_eq!(gltf.images().count(), 1);
    let prim = gltf
        .meshes()
        .next()
        .and_then(|m| m.primitives().next())
        .expect("primitive");
    assert_eq!(
        prim.indices().map(|a| a.data_type()),
        Some(gltf::accessor::DataType::U32)
    );
    assert_eq!(
        prim.material().alpha_mode(),
        gltf::material::AlphaMode::Mask
    );
    let extras: JsonValue = serde_json::from_str(
        gltf.document
            .as_json()
            .extras
            .as_ref()
            .expect("extras")
            .get(),
    )
    .expect("json");
    assert_eq!(extras["pge"]["seed"], 7);
    assert_eq!(extras["pge"]["params"]["h"], 2);
    assert_eq!(extras["pge"]["stats"]["triangles"], 2);
    let mesh_extras: JsonValue = serde_json::from_str(
        gltf.meshes()
            .next()
            .expect("mesh")
            .extras()
            .as_ref()
            .expect("extras")
            .get(),
    )
    .expect("json");
    assert_eq!(mesh_extras["pge"]["skeleton"]["parents"], json!([-1, 0]));
}

#[test]
fn colours_are_normalized_bytes_and_untextured_meshes_have_no_uvs() {
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
    mesh.colors = vec![
        glam::Vec4::new(1.0, 0.0, 0.5, 1.0),
        glam::Vec4::new(0.2, 0.4, 0.6, 0.8),
        glam::Vec4::new(0.0, 1.0, 0.0, 0.0),
    ];
    let bytes = glb_bytes(&Model::from_mesh(mesh), &ExportMeta::default()).expect("glb");
    let (doc, buffers, _) = gltf::import_slice(&bytes).expect("parses");
    let prim = doc
        .meshes()
        .next()
        .and_then(|m| m.primitives().next())
        .expect("primitive");
    let colour = prim
        .get(&gltf::Semantic::Colors(0))
        .expect("a colour accessor");
    assert_eq!(colour.data_type(), gltf::accessor::DataType::U8);
    assert!(colour.normalized());
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let read: Vec<[u8; 4]> = reader
        .read_colors(0)
        .expect("colours")
        .into_rgba_u8()
        .collect();
    assert_eq!(
        read,
        [[255, 0, 128, 255], [51, 102, 153, 204], [0, 255, 0, 0]]
    );
    assert!(
        reader.read_tex_coords(0).is_none(),
        "no texture, so no texture coordinates"
    );
    // A textured mesh keeps its coordinates.
    let (doc, buffers, _) =
        gltf::import_slice(glb_bytes(&textured_model(), &ExportMeta::default()).expect("glb"))
            .expect("parses");
    let prim = doc
        .meshes()
        .next()
        .and_then(|m| m.primitives().next())
        .expect("primitive");
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    assert_eq!(
        reader.read_tex_coords(0).expect("uvs").into_f32().count(),
        3
    );
}

#[test]
fn export_is_byte_identical() {
    let a = glb_bytes(&textured_model(), &ExportMeta::default()).expect("exports");
    let b = glb_bytes(&textured_model(), &ExportMeta::default()).expect("exports");
    assert_eq!(a, b);
    assert_eq!(a.len() % 4, 0);
}

#[test]
fn translucent_materials_carry_diffuse_transmission() {
    let mut model = textured_model();
    let mut mesh = (*model.meshes[0]).clone();
    mesh.material = Arc::new(Material {
        transmission: Some(DiffuseTransmission {
            factor: 0.25,
            color: [0.5, 0.75, 0.125],
        }),
        ..(*mesh.material).clone()
    });
    model.meshes[0] = Arc::new(mesh);
    // An environment too: its unlit sky material and the leaf's extension side by side.
    model.environment = Some(Arc::new(
        Texture::from_rgba("sky", 1, 1, &[9, 9, 200, 255]).expect("png"),
    ));
    let bytes = glb_bytes(&model, &ExportMeta::default()).expect("exports");
    let glb = gltf::binary::Glb::from_slice(&bytes).expect("glb");
    let json: JsonValue = serde_json::from_slice(&glb.json).expect("json");
    let used = json["extensionsUsed"].as_array().expect("extensionsUsed");
    assert!(used.contains(&json!(DIFFUSE_TRANSMISSION)), "{used:?}");
    assert!(used.contains(&json!(UNLIT)), "{used:?}");
    assert!(json.get("extensionsRequired").is_none(), "optional");
    let materials = json["materials"].as_array().expect("materials");
    let with = |name: &str| {
        materials
            .iter()
            .filter(|m| m["extensions"].get(name).is_some())
            .count()
    };
    assert_eq!((with(DIFFUSE_TRANSMISSION), with(UNLIT)), (1, 1));
    let leaf = materials
        .iter()
        .find_map(|m| m["extensions"].get(DIFFUSE_TRANSMISSION))
        .expect("the leaf material's extension");
    assert_eq!(leaf["diffuseTransmissionFactor"], json!(0.25));
    assert_eq!(
        leaf["diffuseTransmissionColorFactor"],
        json!([0.5, 0.75, 0.125])
    );
    // Still a glTF the gltf crate reads.
    gltf::Gltf::from_slice(&bytes).expect("parses");
}

/// A writer that takes at most a few hundred bytes a call, from the first slice only (as a
/// pipe or a socket may).
struct Trickle(Vec<u8>);

impl std::io::Write for Trickle {
    fn write(&mut self, buf: &[u8]) -> std::io::Result<usize> {
        let n = buf.len().min(333);
        self.0.extend_from_slice(&buf[..n]);
        Ok(n)
    }

    fn flush(&mut self) -> std::io::Result<()> {
        Ok(())
    }
}

#[test]
fn a_streamed_file_has_the_bytes_of_the_assembled_one() {
    use crate::geometry::InstanceTransform;
    // Large enough that the colours are converted in pieces and the skeleton is formatted
    // in several: a strip of 70,000 vertices with normals, uvs, colours and a texture.
    let n = 35_000u32;
    let positions: Vec<Vec3> = (0..2 * n)
        .map(|k| Vec3::new((k / 2) as f32 * 0.01, (k % 2) as f32, math::sin(k as f32)))
        .collect();
    let indices = (0..n - 1)
        .flat_map(|i| [2 * i, 2 * i + 1, 2 * i + 2, 2 * i + 2, 2 * i + 1, 2 * i + 3])
        .collect();
    let mut mesh = Mesh::from_triangles(positions, indices).expect("valid");
    mesh.compute_normals();
    mesh.uvs = mesh.positions.iter().map(|p| Vec2::new(p.x, p.y)).collect();
    mesh.colors = mesh
        .positions
        .iter()
        .map(|p| glam::Vec4::new(p.z.abs(), 0.5, p.y, 1.0))
        .collect();
    mesh.material = textured_model().meshes[0].material.clone();
    let mut s = Skeleton::new();
    let mut parent = None;
    for k in 0..5_000 {
        parent = Some(s.push(Vec3::splat(k as f32 * 0.1), parent, 0.01, k % 3));
    }
    mesh.skeleton = Some(Arc::new(s));
    let mut model = textured_model();
    model.add_mesh(Arc::new(mesh), Mat4::from_translation(Vec3::Z));
    model.groups.push(InstanceGroup {
        name: "copies".into(),
        meshes: vec![0],
        transforms: (0..3)
            .map(|k| InstanceTransform {
                translation: [k as f32, 0.0, 0.0],
                rotation: [0.0, 0.0, 0.0, 1.0],
                scale: 1.5,
            })
            .collect(),
        leaves: None,
    });
    model.environment = Some(Arc::new(
        Texture::from_rgba("sky", 1, 1, &[9, 9, 200, 255]).expect("png"),
    ));
    let meta = ExportMeta {
        seed: 3,
        params: vec![("h".into(), json!(2.5))],
    };
    for instancing in [Instancing::Gpu, Instancing::Nodes] {
        let bytes = glb_bytes_with(&model, &meta, instancing).expect("exports");
        let file = glb_file_with(&model, &meta, instancing).expect("exports");
        assert_eq!(file.len(), bytes.len() as u64);
        let mut streamed = Trickle(Vec::new());
        file.write_to(&mut streamed).expect("written");
        assert!(
            streamed.0 == bytes,
            "{instancing:?}: the streamed file differs"
        );
        let mut whole = Vec::new();
        file.write_to(&mut whole).expect("written");
        assert!(
            whole == bytes,
            "{instancing:?}: the file written at once differs"
        );
    }
    // Written as `pge run` writes it: built and written by a thread outside the pool (the
    // colours converted on the pool meanwhile), and everything on the one thread of a pool.
    let bytes = glb_bytes(&model, &meta).expect("exports");
    let through = || {
        write_glb_with(
            &model,
            &Prepared::default(),
            &meta,
            Instancing::Gpu,
            || Ok::<_, Error>(Trickle(Vec::new())),
            |mut out, glb| {
                glb.write_to(&mut out)
                    .map_err(|e| Error::Export(e.to_string()))?;
                Ok(out.0)
            },
        )
        .expect("written")
    };
    assert!(through() == bytes, "written from outside the pool");
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    assert!(one.install(through) == bytes, "written on one thread");
    // An empty model: no binary chunk.
    let file = glb_file_with(&Model::new(), &meta, Instancing::Gpu).expect("exports");
    let mut streamed = Vec::new();
    file.write_to(&mut streamed).expect("written");
    assert_eq!(streamed, file.to_vec().expect("bytes"));
}

/// Bounds found one axis at a time with `f32::min` and `f32::max`, point by point.
fn one_axis_at_a_time(points: &[Vec3]) -> ([u32; 3], [u32; 3]) {
    let mut lo = [f32::INFINITY; 3];
    let mut hi = [f32::NEG_INFINITY; 3];
    for p in points {
        for (k, c) in p.to_array().into_iter().enumerate() {
            lo[k] = lo[k].min(c);
            hi[k] = hi[k].max(c);
        }
    }
    (lo.map(f32::to_bits), hi.map(f32::to_bits))
}

#[test]
fn bounds_four_points_at_a_time_are_the_one_pass_fold_to_the_bit() {
    // Every length up to 40 (the lanes and the last points one at a time), with coordinates
    // drawn from a few values that tie (signed zeros), skip (NaN) and bound (infinities), in
    // every lane.
    let values = [
        -0.0,
        0.0,
        1.0,
        -1.0,
        f32::NAN,
        2.5,
        f32::INFINITY,
        f32::NEG_INFINITY,
        0.0,
        -0.0,
        3.0,
    ];
    let mut state = 0x9e37_79b9_7f4a_7c15u64;
    let mut draw = || {
        state ^= state << 13;
        state ^= state >> 7;
        state ^= state << 17;
        values[(state % values.len() as u64) as usize]
    };
    let bits = |a: [f32; 3]| a.map(f32::to_bits);
    for len in 0..=40 {
        for _ in 0..50 {
            let points: Vec<Vec3> = (0..len)
                .map(|_| Vec3::new(draw(), draw(), draw()))
                .collect();
            let (lo, hi) = vec3_bounds(&points);
            assert_eq!(
                (bits(lo), bits(hi)),
                one_axis_at_a_time(&points),
                "{points:?}"
            );
        }
    }
}

#[test]
fn bounds_in_pieces_are_the_one_pass_fold_to_the_bit() {
    // Enough points for several pieces, with signed zeros at the minimum and the maximum.
    let points: Vec<Vec3> = (0..5 * BOUNDS_PIECE)
        .map(|k| {
            let zero = if k % 3 == 0 { -0.0 } else { 0.0 };
            Vec3::new(
                math::sin(k as f32 * 0.37),
                zero,
                -(k as f32).abs() * 1e-3 + zero,
            )
        })
        .collect();
    let (plo, phi) = vec3_bounds(&points);
    let bits = |a: [f32; 3]| a.map(f32::to_bits);
    assert_eq!((bits(plo), bits(phi)), one_axis_at_a_time(&points));
}

#[test]
fn bounds_keep_the_first_zero_of_a_tie_and_skip_nan_as_f32_min_does() {
    let nan = f32::NAN;
    let sets = [
        vec![Vec3::new(0.0, -0.0, 1.0), Vec3::new(-0.0, 0.0, nan)],
        vec![Vec3::new(-0.0, 0.0, nan), Vec3::new(0.0, -0.0, -1.0)],
        vec![Vec3::NAN, Vec3::new(nan, 2.0, -0.0)],
        vec![Vec3::NAN],
        vec![],
    ];
    let bits = |a: [f32; 3]| a.map(f32::to_bits);
    for points in sets {
        let (lo, hi) = vec3_bounds(&points);
        assert_eq!(
            (bits(lo), bits(hi)),
            one_axis_at_a_time(&points),
            "{points:?}"
        );
    }
}

#[test]
fn an_invalid_model_gets_the_checks_error_and_no_file() {
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.indices = vec![0, 1, 7];
    let mut model = Model::new();
    model.add_mesh(Arc::new(mesh), Mat4::IDENTITY);
    // An instance of a mesh that does not exist, which building alone would also refuse.
    model.instances.push(crate::geometry::Instance {
        mesh: 5,
        transform: Mat4::IDENTITY,
    });
    let err = glb_file_with(&model, &ExportMeta::default(), Instancing::Gpu)
        .err()
        .expect("invalid");
    let want = Error::from(model.validate().expect_err("invalid"));
    assert_eq!(err.to_string(), want.to_string());
    // Written while the check runs: what was opened and written is dropped, the check's
    // error returned.
    let written = write_glb_with(
        &model,
        &Prepared::default(),
        &ExportMeta::default(),
        Instancing::Gpu,
        || Ok::<_, Error>(vec![1u8]),
        |mut out, glb| {
            out.extend(glb.to_vec()?);
            Ok(out)
        },
    );
    assert_eq!(written.err().map(|e| e.to_string()), Some(want.to_string()));
    // On one thread the check runs first: nothing is opened.
    let opened = std::sync::atomic::AtomicBool::new(false);
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a pool");
    let written = one.install(|| {
        write_glb_with(
            &model,
            &Prepared::default(),
            &ExportMeta::default(),
            Instancing::Gpu,
            || {
                opened.store(true, std::sync::atomic::Ordering::Relaxed);
                Ok::<_, Error>(())
            },
            |(), glb| Ok(glb.len()),
        )
    });
    assert_eq!(written.err().map(|e| e.to_string()), Some(want.to_string()));
    assert!(!opened.load(std::sync::atomic::Ordering::Relaxed));
}

#[test]
fn the_calling_thread_opens_the_file_when_the_pool_is_busy() {
    use std::sync::{Barrier, Mutex, mpsc};
    let threads = rayon::current_num_threads();
    if threads == 1 {
        // Everything runs on the calling thread (the test above).
        return;
    }
    let model = textured_model();
    let meta = ExportMeta::default();
    let want = glb_bytes(&model, &meta).expect("exports");
    // Every thread of the pool waits until the file is being written (or, should the
    // calling thread wait for the pool to open it, five seconds).
    let started = Arc::new(Barrier::new(threads + 1));
    let (release, released) = mpsc::channel::<()>();
    let released = Arc::new(Mutex::new(released));
    rayon::spawn_broadcast({
        let started = started.clone();
        move |_| {
            started.wait();
            let released = released.lock().expect("lock");
            let _ = released.recv_timeout(std::time::Duration::from_secs(5));
        }
    });
    started.wait();
    let opened_on = Mutex::new(Vec::new());
    let written = write_glb_with(
        &model,
        &Prepared::default(),
        &meta,
        Instancing::Gpu,
        || {
            opened_on
                .lock()
                .expect("lock")
                .push(std::thread::current().id());
            Ok::<_, Error>(Vec::new())
        },
        |mut out, glb| {
            for _ in 0..threads {
                let _ = release.send(());
            }
            out.extend(glb.to_vec()?);
            Ok(out)
        },
    );
    assert!(written.expect("written") == want);
    // Opened once, by the calling thread: the pool's threads were all busy.
    let opened_on = opened_on.into_inner().expect("lock");
    assert_eq!(opened_on, vec![std::thread::current().id()]);
}

#[test]
fn a_glb_export_stops_at_the_run_s_deadline_before_anything_is_written() {
    use crate::export::ExportLimit;
    use crate::geometry::InstanceTransform;
    use crate::{Location, RunContext};

    // A forest's group of 200,000 placements, written one node each or as one instanced
    // node.
    let mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    let mut model = Model::new();
    model.meshes.push(Arc::new(mesh));
    model.groups.push(InstanceGroup {
        name: "oak/0".into(),
        meshes: vec![0],
        transforms: (0..200_000)
            .map(|i| InstanceTransform {
                translation: [i as f32, 0.0, 0.0],
                rotation: [0.0, 0.0, 0.0, 1.0],
                scale: 1.0,
            })
            .collect(),
        leaves: None,
    });
    let write = |limit: &ExportLimit, instancing| {
        let written = std::sync::atomic::AtomicBool::new(false);
        let out = write_glb_checked(
            &model,
            &Prepared::default(),
            &ExportMeta::default(),
            instancing,
            limit,
            || Ok::<_, Error>(()),
            |(), glb| {
                written.store(true, std::sync::atomic::Ordering::Relaxed);
                glb.to_vec()
            },
        );
        (out, written.into_inner())
    };
    let at = Location::new("forest.lua", 3);
    let passed = ExportLimit {
        ctx: RunContext {
            deadline: Some(crate::clock::Instant::now()),
            ..RunContext::default()
        },
        at: at.clone(),
    };
    for instancing in [Instancing::Gpu, Instancing::Nodes] {
        let (out, written) = write(&passed, instancing);
        let err = out.expect_err("past the deadline");
        assert!(
            matches!(&err, Error::TimeLimit { location } if *location == at),
            "{err:?}"
        );
        assert!(!written, "nothing handed to the writer");
        // Within the deadline, the bytes of the unchecked writer.
        let (out, written) = write(&ExportLimit::default(), instancing);
        assert!(written);
        let plain = glb_bytes_with(&model, &ExportMeta::default(), instancing).expect("glb");
        assert_eq!(out.expect("glb"), plain);
    }
}
