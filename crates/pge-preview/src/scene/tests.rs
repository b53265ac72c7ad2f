use pge_engine::geometry::{Material, Skeleton};
use pge_engine::math;

use super::*;

fn triangle() -> Mesh {
    Mesh::from_triangles(vec![Vec3::ZERO, Vec3::X, Vec3::Y], vec![0, 1, 2]).expect("valid")
}

#[test]
fn instances_are_grouped_per_mesh_and_counted() {
    let tri = Arc::new(triangle());
    let mut model = Model::new();
    model.add_mesh(tri.clone(), Mat4::IDENTITY);
    model.add_mesh(tri, Mat4::from_translation(Vec3::new(5.0, 0.0, 0.0)));
    let scene = Scene::new(&model);
    assert_eq!(scene.meshes.len(), 1);
    assert_eq!(scene.meshes[0].instances.len(), 2);
    assert_eq!(scene.meshes[0].instances[1][12], 5.0, "translation column");
    assert_eq!(scene.meshes[0].vertices.len(), 3 * VERTEX_FLOATS);
    // Vertex 1: position (1,0,0), normal +Z, no uv, white, no tangent (no normal map).
    assert_eq!(
        &scene.meshes[0].vertices[VERTEX_FLOATS..2 * VERTEX_FLOATS],
        &[
            1., 0., 0., 0., 0., 1., 0., 0., 1., 1., 1., 1., 0., 0., 0., 0.
        ]
    );
    assert_eq!(scene.stats.triangles, 2);
    assert_eq!(scene.stats.vertices, 6);
    assert_eq!(scene.bounds, Some((Vec3::ZERO, Vec3::new(6.0, 1.0, 0.0))));
    assert!(!scene.meshes[0].is_leaf);
}

#[test]
fn skeleton_becomes_world_segments_and_leaves_are_recognised() {
    let mut bark = triangle();
    bark.skeleton = Some(Arc::new(Skeleton {
        positions: vec![Vec3::ZERO, Vec3::Y, Vec3::new(1.0, 2.0, 0.0)],
        parents: vec![None, Some(0), Some(1)],
        radii: vec![0.1; 3],
        orders: vec![0; 3],
        ..Skeleton::default()
    }));
    let mut leaves = triangle();
    leaves.material = Arc::new(Material {
        alpha: AlphaMode::Mask(0.5),
        ..Material::default()
    });
    let mut model = Model::new();
    model.add_mesh(bark, Mat4::from_translation(Vec3::Z));
    model.add_mesh(leaves, Mat4::IDENTITY);
    let scene = Scene::new(&model);
    assert_eq!(
        scene.skeleton,
        vec![[0., 0., 1.], [0., 1., 1.], [0., 1., 1.], [1., 2., 1.]]
    );
    assert!(scene.meshes[1].is_leaf);
    let (coarse_vertices, coarse_indices) = scene.meshes[1].coarse.as_ref().expect("foliage");
    assert_eq!(coarse_indices, &[0, 1, 2]);
    // One triangle, grown by sqrt(COARSE_KEEP / 2) about its centre (1/3, 1/3).
    let grown: Vec<f32> = coarse_vertices
        .chunks(VERTEX_FLOATS)
        .flat_map(|v| v[0..3].to_vec())
        .collect();
    let (t, g) = (1.0 / 3.0, (COARSE_KEEP as f32 / 2.0).sqrt());
    let expect = [
        t - t * g,
        t - t * g,
        0.0,
        t + (1.0 - t) * g,
        t - t * g,
        0.0,
        t - t * g,
        t + (1.0 - t) * g,
        0.0,
    ];
    assert!(
        grown.iter().zip(expect).all(|(a, b)| (a - b).abs() < 1e-5),
        "{grown:?}"
    );
    assert_eq!(scene.meshes[0].coarse, None);
    let vertices: Vec<f32> = (0..4 * VERTEX_FLOATS).map(|i| i as f32).collect();
    let (v, i) = compact(&vertices, &[3, 1, 3]);
    assert_eq!(i, vec![0, 1, 0]);
    assert_eq!(v[0], (3 * VERTEX_FLOATS) as f32);
    assert_eq!(v[VERTEX_FLOATS], VERTEX_FLOATS as f32);
    assert_eq!(v.len(), 2 * VERTEX_FLOATS);
    assert_eq!(
        coarse(&(0..60).collect::<Vec<u32>>()),
        vec![0, 1, 2, 3, 4, 5, 48, 49, 50, 51, 52, 53]
    );
    assert_eq!(scene.meshes[1].alpha_cutoff, Some(0.5));
}

#[test]
fn big_bark_keeps_its_largest_eighth_while_moving() {
    // Triangle k has legs of length k + 1: the largest are the last ones.
    let n = COARSE_BARK_MIN as u32;
    let mut vertices = Vec::new();
    for k in 0..n {
        let s = (k + 1) as f32;
        for p in [[0.0, 0.0, 0.0], [s, 0.0, 0.0], [0.0, s, 0.0]] {
            vertices.extend_from_slice(&p);
            vertices.extend_from_slice(&[0.0; VERTEX_FLOATS - 3]);
        }
    }
    let indices: Vec<u32> = (0..3 * n).collect();
    let (v, i) = coarse_bark(&vertices, &indices, 1).expect("big enough");
    assert_eq!(i.len() / 3, (n / 8) as usize);
    assert_eq!(v.len(), i.len() * VERTEX_FLOATS);
    assert!(
        v.chunks(VERTEX_FLOATS)
            .all(|p| p[0] == 0.0 || p[0] > (n - n / 8) as f32)
    );
    assert_eq!(
        coarse_bark(&vertices[..9 * VERTEX_FLOATS], &[0, 1, 2], 1),
        None
    );
    // A small bush instanced by the thousand (a forest's) draws many triangles: coarse.
    let small = &indices[..3 * 1000];
    assert_eq!(coarse_bark(&vertices, small, 1), None);
    let (_, i) = coarse_bark(&vertices, small, 5000).expect("drawn often enough");
    assert_eq!(i.len() / 3, 1000 / 8);
}

#[test]
fn a_terrains_coarse_version_covers_every_cell_without_holes() {
    use pge_forest::{FbmOptions, Terrain};
    // A forest's terrain, 126 by 116 cells (the last ones narrower), hilly.
    let options = FbmOptions {
        height: 30.0,
        scale: 80.0,
        ..FbmOptions::default()
    };
    let terrain = Terrain::fbm([502.0, 463.0], options, 7);
    let grid = terrain.grid(None);
    let (kx, kz) = terrain.patch(&grid, None);
    let mesh = terrain.mesh(&grid, kx, kz);
    let full = mesh.indices.len() / 3;
    assert_eq!(full, 2 * 126 * 116);
    let mut model = Model::new();
    model.add_mesh(mesh, Mat4::IDENTITY);
    let scene = Scene::new(&model);
    let (vertices, indices) = scene.meshes[0].coarse.as_ref().expect("a coarse version");
    let coarse = indices.len() / 3;
    assert!(
        coarse > 0 && coarse <= full / 8,
        "{coarse} of {full} triangles"
    );
    let at = |i: u32| {
        let v = &vertices[i as usize * VERTEX_FLOATS..];
        glam::Vec2::new(v[0], v[2])
    };
    // Seen from above, the triangles turn the same way and their areas add up to the
    // terrain's: they cover it once...
    let mut area = 0.0f64;
    for t in indices.chunks_exact(3) {
        let (a, b, c) = (at(t[0]), at(t[1]), at(t[2]));
        let twice = (b - a).perp_dot(c - a);
        assert!(twice < 0.0, "every triangle faces up: {t:?}");
        area += f64::from(-twice) / 2.0;
    }
    assert!((area - 502.0 * 463.0).abs() < 1.0, "area {area}");
    // ...and each edge is shared by two triangles, but those on the terrain's border.
    let mut edges: HashMap<(u32, u32), u32> = HashMap::new();
    for t in indices.chunks_exact(3) {
        for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
            *edges.entry((a.min(b), a.max(b))).or_default() += 1;
        }
    }
    let on_border =
        |p: glam::Vec2| (p.x.abs() - 251.0).abs() < 1e-3 || (p.y.abs() - 231.5).abs() < 1e-3;
    for (&(a, b), &n) in &edges {
        let border = on_border(at(a)) && on_border(at(b)) && {
            let (p, q) = (at(a), at(b));
            (p.x - q.x).abs() < 1e-3 || (p.y - q.y).abs() < 1e-3
        };
        assert_eq!(
            n,
            if border { 1 } else { 2 },
            "edge {:?}-{:?}",
            at(a),
            at(b)
        );
    }
    // Its vertices are the terrain's own.
    let heights: Vec<f32> = scene.meshes[0]
        .vertices
        .chunks(VERTEX_FLOATS)
        .map(|v| v[1])
        .collect();
    assert!(
        vertices
            .chunks(VERTEX_FLOATS)
            .all(|v| heights.contains(&v[1]))
    );
}

#[test]
fn a_forests_leaves_get_levels_and_its_meshes_are_marked() {
    use pge_engine::geometry::{InstanceGroup, InstanceTransform};
    // A crown of 40 small square leaves on a ring, and a trunk.
    let mut leaves = Mesh::default();
    for i in 0..40u32 {
        let t = i as f32 / 40.0 * std::f32::consts::TAU;
        let (c, n) = (
            Vec3::new(math::cos(t), 2.0 + 0.1 * (i % 3) as f32, math::sin(t)),
            Vec3::new(math::cos(t), 0.0, math::sin(t)),
        );
        let side = n.cross(Vec3::Y) * 0.2;
        let up = Vec3::Y * 0.2;
        leaves.positions.extend_from_slice(&[
            c - side - up,
            c + side - up,
            c + side + up,
            c - side + up,
        ]);
        leaves.normals.extend_from_slice(&[n; 4]);
        let b = 4 * i;
        leaves
            .indices
            .extend_from_slice(&[b, b + 1, b + 2, b, b + 2, b + 3]);
    }
    leaves.material = Arc::new(Material {
        alpha: AlphaMode::Mask(0.5),
        ..Material::default()
    });
    let trunk = triangle();
    let mut model = Model::new();
    model.meshes.push(Arc::new(trunk));
    model.meshes.push(Arc::new(leaves));
    let at = |x: f32| InstanceTransform {
        translation: [x, 0.0, 0.0],
        rotation: [0.0, 0.0, 0.0, 1.0],
        scale: 2.0,
    };
    model.groups.push(InstanceGroup {
        name: "tree/1".into(),
        meshes: vec![0, 1],
        transforms: vec![at(0.0), at(10.0), at(-30.0)],
        leaves: None,
    });
    assert!(model.meshes[1].lod.is_none());
    let scene = Scene::new(&model);
    assert!(
        scene
            .meshes
            .iter()
            .all(|m| m.forest && m.instances.len() == 3)
    );
    assert!(scene.meshes[0].lod.is_none(), "bark has no levels");
    let lod = scene.meshes[1]
        .lod
        .as_ref()
        .expect("levels computed for the forest");
    assert_eq!(lod.leaves(), 40);
    assert!(lod.roots() < 40, "{} roots", lod.roots());
    // The finest level draws the original leaves; V holds them and the collapsed ones.
    assert_eq!(scene.meshes[1].indices.len(), 6 * 40);
    assert_eq!(
        scene.meshes[1].vertices.len(),
        4 * (80 - lod.roots() as usize) * VERTEX_FLOATS
    );
    // The bounds are the model's, found without visiting every vertex per instance.
    assert_eq!(scene.bounds, model.bounds());
    // The sphere holds every vertex.
    let (centre, radius) = scene.meshes[1].sphere;
    assert!(
        model.meshes[1]
            .positions
            .iter()
            .all(|p| p.distance(centre) <= radius + 1e-5)
    );
    // Placed on its own, the same mesh is a plain mesh.
    let plain = Scene::new(&Model::from_mesh(model.meshes[1].clone()));
    assert!(!plain.meshes[0].forest && plain.meshes[0].lod.is_none());
    // Leaves that carry their table (the species' or the forest's `lod`, as the glb's
    // `Mesh::lod`) are read as they are, not simplified again: four sectors here,
    // where the preview's own levels would have one.
    let options = pge_lod::LodOptions {
        sectors: 4,
        ..pge_lod::LodOptions::default()
    };
    let (with_table, _) = pge_lod::lod_mesh(&model.meshes[1], &options).expect("lod");
    let table =
        super::super::lod::LeafLod::from_lod(with_table.lod.as_deref(), with_table.positions.len())
            .expect("the table");
    let mut model = model;
    model.meshes[1] = Arc::new(with_table);
    let scene = Scene::new(&model);
    assert_eq!(scene.meshes[1].lod.as_ref(), Some(&table));
    assert_ne!(
        Some(&table),
        Some(lod),
        "the table is not the preview's own"
    );
}

#[test]
fn the_environment_is_decoded_with_its_average_colour() {
    let mut model = Model::from_mesh(triangle());
    assert!(Scene::new(&model).environment.is_none());
    // Half white, half black: the linear average is one half.
    let rgba = [255, 255, 255, 255, 0, 0, 0, 255];
    model.environment = Some(Arc::new(
        Texture::from_rgba("sky", 2, 1, &rgba).expect("png"),
    ));
    let scene = Scene::new(&model);
    let env = scene.environment.as_ref().expect("decoded");
    assert_eq!((env.texture.width, env.texture.height), (2, 1));
    assert!(
        env.average.iter().all(|c| (c - 0.5).abs() < 1e-6),
        "{:?}",
        env.average
    );
}

#[test]
fn textures_are_decoded_with_a_full_mip_chain() {
    let mut rgba = Vec::new();
    for i in 0..(4 * 2) {
        rgba.extend_from_slice(if i % 2 == 0 {
            &[255, 0, 0, 255]
        } else {
            &[0, 0, 255, 0]
        });
    }
    let tex = Arc::new(Texture::from_rgba("t", 4, 2, &rgba).expect("png"));
    let mut mesh = triangle();
    mesh.material = Arc::new(Material {
        texture: Some(tex),
        ..Material::default()
    });
    let scene = Scene::new(&Model::from_mesh(mesh));
    let data = scene.meshes[0].texture.as_ref().expect("decoded");
    assert_eq!((data.width, data.height), (4, 2));
    let sizes: Vec<usize> = data.levels.iter().map(Vec::len).collect();
    assert_eq!(sizes, vec![32, 8, 4], "4x2, 2x1, 1x1");
    // Averaging red and transparent blue gives half alpha and gamma-correct halves.
    assert_eq!(&data.levels[1][0..4], &[186, 0, 186, 128]);
}

#[test]
fn a_normal_mapped_mesh_carries_the_glb_tangents_and_its_map() {
    let mut mesh = triangle();
    mesh.uvs = vec![glam::Vec2::ZERO, glam::Vec2::X, glam::Vec2::Y];
    let map =
        Texture::from_rgba("bark normal", 2, 2, &[128, 128, 255, 255].repeat(4)).expect("png");
    mesh.material = Arc::new(Material {
        normal_texture: Some(Arc::new(map)),
        ..Material::default()
    });
    let tangents = mesh.tangents().expect("a normal-mapped mesh has tangents");
    let scene = Scene::new(&Model::from_mesh(mesh));
    let drawn = &scene.meshes[0];
    for (i, t) in tangents.iter().enumerate() {
        let at = i * VERTEX_FLOATS + 12;
        assert_eq!(&drawn.vertices[at..at + 4], &t.to_array(), "vertex {i}");
    }
    // u grows along +X here: the tangent is +X, the bitangent (+Y) on the positive side.
    assert_eq!(tangents[0], glam::Vec4::new(1.0, 0.0, 0.0, 1.0));
    let map = drawn.normal_texture.as_ref().expect("the map is decoded");
    assert_eq!((map.width, map.height, map.levels.len()), (2, 2, 2));
    assert_eq!(
        map.levels[1],
        [128, 128, 255, 255],
        "a plain box filter of the data"
    );
    assert!(scene.meshes[0].texture.is_none());
}
