use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3, Vec4};

use super::*;
use crate::geometry::{InstanceTransform, Material};

fn triangle() -> Mesh {
    let mut mesh = Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2])
        .expect("a triangle");
    mesh.name = "bark".into();
    mesh.normals = vec![Vec3::Z; 3];
    mesh.uvs = vec![Vec2::ZERO, Vec2::X, Vec2::Y];
    mesh
}

fn meta() -> ExportMeta {
    ExportMeta {
        seed: 7,
        params: vec![
            ("height".into(), json!(12.5)),
            ("name".into(), json!("oak")),
        ],
    }
}

fn count(text: &str, needle: &str) -> usize {
    text.matches(needle).count()
}

#[test]
fn a_mesh_has_its_points_faces_normals_and_st() {
    let files = usd_files(&Model::from_mesh(triangle()), &meta(), "tree").expect("exports");
    let l = &files.layer;
    assert!(
        l.starts_with("#usda 1.0\n(\n    defaultPrim = \"PGE\""),
        "{l}"
    );
    assert!(l.contains("metersPerUnit = 1") && l.contains("upAxis = \"Y\""));
    assert!(l.contains("def Mesh \"bark\""));
    assert!(l.contains("int[] faceVertexCounts = [3]"));
    assert!(l.contains("int[] faceVertexIndices = [0, 1, 2]"));
    assert!(l.contains("point3f[] points = [(0.0, 0.0, 0.0), (1.0, 0.0, 0.0), (0.0, 1.0, 0.0)]"));
    assert!(l.contains("normal3f[] normals = [(0.0, 0.0, 1.0), (0.0, 0.0, 1.0), (0.0, 0.0, 1.0)]"));
    // v flipped: glTF's (0, 1) is USD's (0, 0).
    assert!(
        l.contains("texCoord2f[] primvars:st = [(0.0, 1.0), (1.0, 1.0), (0.0, 0.0)]"),
        "{l}"
    );
    assert!(l.contains("uint64 \"seed\" = 7") || l.contains("int64 \"seed\" = 7"));
    assert!(l.contains("double \"height\" = 12.5"));
    assert!(!l.contains("xformOp"), "the identity is not written");
    assert!(!l.contains("displayColor"), "no colours, no displayColor");
    assert!(files.textures.is_empty());
}

#[test]
fn colours_transforms_and_textures_are_written() {
    let mut mesh = triangle();
    mesh.colors = vec![Vec4::new(1.0, 0.5, 0.25, 1.0); 3];
    let texture = Arc::new(Texture::from_rgba("leaf", 1, 1, &[0, 255, 0, 128]).expect("png"));
    mesh.material = Arc::new(Material {
        name: "leaf".into(),
        texture: Some(texture.clone()),
        normal_texture: Some(texture),
        alpha: AlphaMode::Mask(0.5),
        ..Material::default()
    });
    let mut model = Model::new();
    model.add_mesh(
        mesh.clone(),
        Mat4::from_translation(Vec3::new(1.0, 2.0, 3.0)),
    );
    model.add_mesh(mesh, Mat4::IDENTITY);
    let files = usd_files(&model, &meta(), "tree").expect("exports");
    let l = &files.layer;
    assert_eq!(files.textures.len(), 1, "one texture, shared");
    assert_eq!(files.textures[0].0, "tree/0_leaf.png");
    assert!(l.contains("asset inputs:file = @./tree/0_leaf.png@"));
    assert_eq!(count(l, "def Material "), 1);
    assert_eq!(count(l, "def Mesh \"bark"), 2);
    assert!(l.contains("def Mesh \"bark_2\""));
    assert!(l.contains("float inputs:opacityThreshold = 0.5"));
    assert!(l.contains("float inputs:opacity.connect = </PGE/Materials/leaf/Color.outputs:a>"));
    assert!(l.contains("token inputs:sourceColorSpace = \"raw\""));
    assert!(l.contains("float4 inputs:bias = (-1.0, -1.0, -1.0, 0.0)"));
    assert!(l.contains("color3f[] primvars:displayColor = [(1.0, 0.5, 0.25)"));
    assert!(l.contains(
        "matrix4d xformOp:transform = ((1.0, 0.0, 0.0, 0.0), (0.0, 1.0, 0.0, 0.0), \
         (0.0, 0.0, 1.0, 0.0), (1.0, 2.0, 3.0, 1.0))"
    ));
    assert_eq!(count(l, "xformOpOrder"), 1);
}

#[test]
fn a_forest_is_a_point_instancer_per_species() {
    let mut model = Model::new();
    for _ in 0..3 {
        model.meshes.push(Arc::new(triangle()));
    }
    let at = |x: f32| InstanceTransform {
        translation: [x, 0.0, 0.0],
        rotation: [0.0, 0.0, 0.0, 1.0],
        scale: 2.0,
    };
    for (k, (name, n)) in [("oak/0", 2), ("oak/1", 1), ("pine/0", 3)]
        .into_iter()
        .enumerate()
    {
        model.groups.push(InstanceGroup {
            name: name.into(),
            meshes: vec![k],
            transforms: (0..n).map(|k| at(k as f32)).collect(),
            leaves: None,
        });
    }
    let l = usd_files(&model, &meta(), "f").expect("exports").layer;
    assert_eq!(count(&l, "def PointInstancer "), 2);
    assert!(l.contains("int[] protoIndices = [0, 0, 1]"), "{l}");
    assert!(l.contains("int[] protoIndices = [0, 0, 0]"));
    assert!(
        l.contains("rel prototypes = [</PGE/oak/Prototypes/oak_0>, </PGE/oak/Prototypes/oak_1>]")
    );
    assert!(l.contains("quath[] orientations = [(1.0, 0.0, 0.0, 0.0), (1.0, 0.0, 0.0, 0.0)"));
    assert!(l.contains("float3[] scales = [(2.0, 2.0, 2.0)"));
    assert_eq!(
        count(&l, "def Mesh \"bark\""),
        3,
        "one prototype per variant"
    );
}

#[test]
fn stages_are_variants_of_the_root() {
    let small = Model::from_mesh(triangle());
    let mut big = Model::from_mesh(triangle());
    big.add_mesh(triangle(), Mat4::IDENTITY);
    let stages = vec![("step 1".to_string(), small), ("step 2".to_string(), big)];
    let l = usd_stages_files(&stages, &meta(), "s")
        .expect("exports")
        .layer;
    assert!(
        l.contains("variants = {\n        string stage = \"step_2\""),
        "{l}"
    );
    assert!(l.contains("prepend variantSets = \"stage\""));
    assert!(l.contains("variantSet \"stage\" = {"));
    assert!(l.contains("\"step_1\" {") || l.contains("\"step_1\"\n"));
    assert_eq!(count(&l, "def Mesh "), 3);
    assert_eq!(count(&l, "def Material "), 1, "materials are shared");
    assert!(usd_stages_files(&[], &meta(), "s").is_err());
}

#[test]
fn the_same_model_gives_the_same_bytes() {
    let a = usd_files(&Model::from_mesh(triangle()), &meta(), "t").expect("exports");
    let b = usd_files(&Model::from_mesh(triangle()), &meta(), "t").expect("exports");
    assert_eq!(a.layer, b.layer);
}
