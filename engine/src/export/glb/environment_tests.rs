//! Tests of the environment image and the sky dome that carries it to clients.

use super::*;
use crate::geometry::{Material, Mesh, Texture};
use glam::{Mat4, Vec2, Vec3};

#[test]
fn the_environment_is_an_embedded_image_named_by_the_root_extras() {
    let mut rgba = Vec::new();
    for _ in 0..2 {
        rgba.extend_from_slice(&[40, 90, 220, 255, 40, 90, 220, 255]);
    }
    for _ in 0..2 {
        rgba.extend_from_slice(&[90, 70, 40, 255, 90, 70, 40, 255]);
    }
    let sky = Arc::new(Texture::from_rgba("sky", 4, 2, &rgba).expect("png"));
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
    let mut model = Model::from_mesh(mesh);
    model.environment = Some(sky.clone());
    let bytes = glb_bytes(&model, &ExportMeta::default()).expect("exports");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
    let extras: JsonValue = serde_json::from_str(
        gltf.document
            .as_json()
            .extras
            .as_ref()
            .expect("extras")
            .get(),
    )
    .expect("json");
    let env = &extras["pge"]["environment"];
    assert_eq!(env["mapping"], "equirectangular");
    let index = env["image"].as_u64().expect("an image index") as usize;
    let image = gltf.images().nth(index).expect("the image exists");
    let gltf::image::Source::View { view, mime_type } = image.source() else {
        panic!("embedded, not a uri");
    };
    assert_eq!(mime_type, "image/png");
    let blob = gltf.blob.as_ref().expect("binary chunk");
    let png = &blob[view.offset()..view.offset() + view.length()];
    assert_eq!(png, sky.encoded.as_slice());
    let decoded = image::load_from_memory(png).expect("png").to_rgba8();
    assert_eq!(decoded.dimensions(), (4, 2));
    assert_eq!(decoded.as_raw(), &rgba);

    // The same picture as a material texture is stored once.
    let mut textured = Model::new();
    let mut mesh =
        Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid");
    mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
    mesh.material = Arc::new(Material {
        texture: Some(Arc::new((*sky).clone())),
        ..Material::default()
    });
    textured.add_mesh(mesh, Mat4::IDENTITY);
    textured.environment = Some(sky);
    let bytes = glb_bytes(&textured, &ExportMeta::default()).expect("exports");
    let gltf = gltf::Gltf::from_slice(&bytes).expect("parses");
    assert_eq!(gltf.images().count(), 1);
    assert_eq!(gltf.textures().count(), 1);
}

#[test]
fn the_environment_is_a_sky_dome_around_the_model() {
    let sky =
        Arc::new(Texture::from_rgba("sky", 2, 1, &[0, 0, 255, 255, 9, 9, 9, 255]).expect("png"));
    let mesh = Mesh::from_triangles(
        vec![
            Vec3::ZERO,
            Vec3::new(20.0, 0.0, 0.0),
            Vec3::new(0.0, 20.0, 0.0),
        ],
        vec![0, 1, 2],
    )
    .expect("valid");
    let mut model = Model::from_mesh(mesh);
    model.environment = Some(sky.clone());
    let bytes = glb_bytes(&model, &ExportMeta::default()).expect("exports");
    let (doc, buffers, images) = gltf::import_slice(&bytes).expect("parses");
    assert_eq!(
        images.len(),
        1,
        "the dome shows the environment image itself"
    );
    let text = String::from_utf8_lossy(&bytes);
    assert!(text.contains("\"extensionsUsed\":[\"KHR_materials_unlit\"]"));
    let scene = doc.default_scene().expect("scene");
    let dome = scene
        .nodes()
        .find(|n| n.name() == Some("sky"))
        .expect("a node named sky");
    let (t, _, s) = dome.transform().decomposed();
    // Centred on the model, ten times as far as its farthest corner.
    assert_eq!(t, [10.0, 10.0, 0.0]);
    let radius = 10.0 * (800.0f32).sqrt() / 2.0;
    assert!((s[0] - radius).abs() < 1e-3, "{s:?}");
    let mesh = dome.mesh().expect("the dome's mesh");
    assert_eq!(mesh.name(), Some("sky"));
    let prim = mesh.primitives().next().expect("primitive");
    let material = prim.material();
    let json: JsonValue = serde_json::from_slice(
        &bytes[20..20 + u32::from_le_bytes([bytes[12], bytes[13], bytes[14], bytes[15]]) as usize],
    )
    .expect("json chunk");
    let index = material.index().expect("a material");
    assert_eq!(json["materials"][index]["extensions"], json!({ UNLIT: {} }));
    let texture = material
        .pbr_metallic_roughness()
        .base_color_texture()
        .expect("textured");
    assert_eq!(texture.texture().source().index(), 0);
    let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
    let p: Vec<Vec3> = reader
        .read_positions()
        .expect("positions")
        .map(Vec3::from)
        .collect();
    let uv: Vec<[f32; 2]> = reader.read_tex_coords(0).expect("uvs").into_f32().collect();
    let idx: Vec<u32> = reader.read_indices().expect("indices").into_u32().collect();
    for (q, [u, v]) in p.iter().zip(&uv) {
        assert!((q.length() - 1.0).abs() < 1e-5);
        // Row 0 straight up; the middle column along -Z, a quarter to its right +X.
        if *v == 0.0 {
            assert!(q.y > 0.999);
        }
        if *v == 0.5 && *u == 0.5 {
            assert!(q.z < -0.999, "{q}");
        }
        if *v == 0.5 && *u == 0.75 {
            assert!(q.x > 0.999, "{q}");
        }
    }
    // Every triangle has an area and faces the centre.
    for t in idx.chunks_exact(3) {
        let [a, b, c] = [t[0], t[1], t[2]].map(|i| p[i as usize]);
        let face = (b - a).cross(c - a);
        assert!(face.length() > 1e-5);
        assert!(face.dot(a + b + c) < 0.0, "faces inward");
    }
}

#[test]
fn without_an_environment_nothing_is_written() {
    let bytes = glb_bytes(&Model::new(), &ExportMeta::default()).expect("exports");
    let text = String::from_utf8_lossy(&bytes);
    assert!(!text.contains("environment"));
}
