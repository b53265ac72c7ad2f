//! Export speed: a 500,000-triangle grid mesh to glb bytes; a small tree like the library's
//! oak (31 k triangles, six embedded textures) and a 2 M-triangle tree-like mesh (normals,
//! colours, a 100,000-node skeleton), to glb bytes and streamed to a file, beside their
//! limit, one copy of the same number of bytes, on every core and on one thread; and a
//! script run end to end.

use pge_engine::math;
use std::io::{Seek, Write};
use std::sync::Arc;

use criterion::{Criterion, Throughput, criterion_group, criterion_main};
use glam::{Vec2, Vec3, Vec4};
use pge_engine::export::{ExportMeta, GlbFile, Instancing, glb_bytes, glb_file_with};
use pge_engine::geometry::{DiffuseTransmission, Material, Mesh, Model, Skeleton, Texture};
use pge_engine::{Engine, SessionOptions};

fn grid(n: u32) -> Mesh {
    let mut positions = Vec::new();
    let mut uvs = Vec::new();
    for j in 0..=n {
        for i in 0..=n {
            positions.push(Vec3::new(i as f32, math::sin((i * j) as f32), j as f32));
            uvs.push(Vec2::new(i as f32 / n as f32, j as f32 / n as f32));
        }
    }
    let mut indices = Vec::new();
    for j in 0..n {
        for i in 0..n {
            let a = j * (n + 1) + i;
            indices.extend_from_slice(&[a, a + n + 1, a + 1, a + 1, a + n + 1, a + n + 2]);
        }
    }
    let mut mesh = Mesh::from_triangles(positions, indices).expect("valid grid");
    mesh.uvs = uvs;
    mesh
}

/// A `n` x `n` grid as a tree's bark mesh: normals, vertex colours and a skeleton of one
/// node per 20 triangles (a tree's bark has 16-32 triangles a node).
fn tree_like(n: u32) -> Mesh {
    let mut mesh = grid(n);
    mesh.normals = mesh
        .positions
        .iter()
        .map(|p| Vec3::new(math::cos(p.y), 1.0, math::sin(p.x)).normalize())
        .collect();
    mesh.colors = mesh
        .positions
        .iter()
        .map(|p| Vec4::new(0.3 + 0.1 * p.y, 0.2, 0.1, 1.0))
        .collect();
    let mut skeleton = Skeleton::new();
    let nodes = mesh.indices.len() / 3 / 20;
    for k in 0..nodes {
        let parent = (k > 0).then(|| ((k - 1) / 2) as u32);
        let t = k as f32 * 0.001;
        let position = Vec3::new(math::sin(t), t * 0.37, math::cos(t));
        skeleton.push(position, parent, 0.3 / (1.0 + t), (k % 7) as u32);
    }
    mesh.skeleton = Some(Arc::new(skeleton));
    mesh
}

/// A texture of `bytes` bytes of PNG (not decoded: the export copies them as they are).
fn png(name: &str, bytes: usize) -> Option<Arc<Texture>> {
    let png = (0..bytes).map(|k| (k * 7919 % 251) as u8).collect();
    Some(Arc::new(Texture {
        name: name.into(),
        width: 512,
        height: 512,
        encoded: png,
    }))
}

/// A tree the size of `scripts/species/oak.lua`'s: bark of 27.4 k triangles (normals,
/// colours, texture coordinates, a 1,370-node skeleton) and leaves of 4.2 k (normals,
/// colours, texture coordinates, diffuse transmission), each with colour, normal and
/// roughness maps of the oak's sizes (1.07 MB of PNG in all).
fn small_tree() -> Model {
    let mut bark = tree_like(117);
    bark.material = Arc::new(Material {
        name: "bark".into(),
        texture: png("bark color", 298_291),
        normal_texture: png("bark normal", 380_336),
        metallic_roughness_texture: png("bark roughness", 184_435),
        ..Material::default()
    });
    let mut leaves = tree_like(46);
    leaves.skeleton = None;
    leaves.material = Arc::new(Material {
        name: "leaves".into(),
        texture: png("leaf color", 88_710),
        normal_texture: png("leaf normal", 86_811),
        metallic_roughness_texture: png("leaf roughness", 36_096),
        double_sided: true,
        transmission: Some(DiffuseTransmission {
            factor: 0.25,
            color: [0.7, 0.8, 0.4],
        }),
        ..Material::default()
    });
    let mut model = Model::from_mesh(Arc::new(bark));
    model.add_mesh(Arc::new(leaves), glam::Mat4::IDENTITY);
    model
}

/// `glb` written over the start of `file` and cut to its length (as a fresh file would be).
fn write_over(glb: &GlbFile, file: &mut std::fs::File) {
    file.rewind().expect("rewinds");
    glb.write_to(file).expect("writes");
    file.set_len(glb.len()).expect("cuts");
    file.flush().expect("flushes");
}

/// The glb of `model` three ways, beside the copy of as many bytes into a fresh buffer:
/// assembled in one buffer (`glb_bytes`), streamed to a sink (building the file and
/// converting what must be converted, no copy) and streamed into a file (the page cache).
fn glb_ways(c: &mut Criterion, group: &str, model: &Model, samples: usize) {
    let meta = ExportMeta::default();
    let size = glb_bytes(model, &meta).expect("exports").len();
    let source = vec![1u8; size];
    let path = concat!(env!("CARGO_TARGET_TMPDIR"), "/export_bench.glb");
    let mut file = std::fs::File::create(path).expect("a scratch file");
    let mut g = c.benchmark_group(group);
    g.throughput(Throughput::Elements(model.triangle_count() as u64));
    g.sample_size(samples);
    g.bench_function("glb_bytes", |b| {
        b.iter(|| glb_bytes(model, &meta).expect("exports"))
    });
    g.bench_function("streamed_to_sink", |b| {
        b.iter(|| {
            let glb = glb_file_with(model, &meta, Instancing::Gpu).expect("exports");
            glb.write_to(&mut std::io::sink()).expect("writes");
        })
    });
    g.bench_function("streamed_to_file", |b| {
        b.iter(|| {
            let glb = glb_file_with(model, &meta, Instancing::Gpu).expect("exports");
            write_over(&glb, &mut file);
        })
    });
    g.bench_function("memcpy_same_bytes", |b| b.iter(|| source.clone()));
    g.bench_function("memcpy_same_bytes_to_file", |b| {
        b.iter(|| {
            file.rewind().expect("rewinds");
            file.write_all(&source).expect("writes");
        })
    });
    g.finish();
    drop(file);
    std::fs::remove_file(path).expect("removes the scratch file");
}

fn export(c: &mut Criterion) {
    glb_ways(c, "export_small_tree", &small_tree(), 50);
    let model = Model::from_mesh(Arc::new(grid(500)));
    let mut g = c.benchmark_group("export");
    g.throughput(Throughput::Elements(model.triangle_count() as u64));
    g.bench_function("glb_500k_triangles", |b| {
        b.iter(|| glb_bytes(&model, &ExportMeta::default()).expect("exports"))
    });
    g.finish();

    // The 2 M-triangle tree and its limit in the same run: copying as many bytes as the
    // glb holds into a fresh buffer (what a writer that only copies would cost).
    let model = Model::from_mesh(Arc::new(tree_like(1000)));
    let size = glb_bytes(&model, &ExportMeta::default())
        .expect("exports")
        .len();
    let source = vec![1u8; size];
    let mut g = c.benchmark_group("export_2m");
    g.throughput(Throughput::Elements(model.triangle_count() as u64));
    g.sample_size(10);
    g.bench_function("glb_tree_2m_triangles", |b| {
        b.iter(|| glb_bytes(&model, &ExportMeta::default()).expect("exports"))
    });
    // The same on one thread (the row above uses every core): the 2-thread speed-up.
    let one = rayon::ThreadPoolBuilder::new()
        .num_threads(1)
        .build()
        .expect("a thread pool");
    g.bench_function("glb_tree_2m_triangles_1_thread", |b| {
        b.iter(|| one.install(|| glb_bytes(&model, &ExportMeta::default()).expect("exports")))
    });
    g.bench_function("memcpy_same_bytes", |b| b.iter(|| source.clone()));
    g.finish();
    glb_ways(c, "export_2m_ways", &model, 10);

    // Finding degenerate and repeated triangles (done before every export of a generated
    // model), on every core and on one thread.
    let mesh = &model.meshes[0];
    let mut g = c.benchmark_group("unusable_triangles_2m");
    g.throughput(Throughput::Elements(mesh.triangle_count() as u64));
    g.sample_size(10);
    g.bench_function("every_core", |b| b.iter(|| mesh.unusable_triangles()));
    g.bench_function("1_thread", |b| {
        b.iter(|| one.install(|| mesh.unusable_triangles()))
    });
    g.bench_function("siphash_set_before", |b| b.iter(|| siphash_set(mesh)));
    g.finish();
}

/// The triangles to remove as the engine found them before its sharded search: one SipHash
/// set of every triangle's corners (the peer of `unusable_triangles_2m`).
fn siphash_set(mesh: &Mesh) -> Vec<usize> {
    let mut seen = std::collections::HashSet::with_capacity(mesh.indices.len() / 3);
    let mut dropped = Vec::new();
    for (t, tri) in mesh.indices.chunks_exact(3).enumerate() {
        let [a, b, c] = [tri[0], tri[1], tri[2]].map(|i| mesh.positions[i as usize]);
        let twice_area = (b - a).cross(c - a).length();
        let longest = (b - a)
            .length_squared()
            .max((c - b).length_squared())
            .max((a - c).length_squared());
        let keys = [a, b, c].map(|p| (p + Vec3::ZERO).to_array().map(f32::to_bits));
        let first = (0..3).min_by_key(|&k| keys[k]).unwrap_or(0);
        let key = [keys[first], keys[(first + 1) % 3], keys[(first + 2) % 3]];
        if twice_area <= 1e-6 * longest || !seen.insert(key) {
            dropped.push(t);
        }
    }
    dropped
}

fn script(c: &mut Criterion) {
    let engine = Engine::builder()
        .library(concat!(env!("CARGO_MANIFEST_DIR"), "/../scripts"))
        .build()
        .expect("engine");
    let path = concat!(
        env!("CARGO_MANIFEST_DIR"),
        "/../scripts/examples/terrain.lua"
    );
    c.bench_function("terrain_script_to_model", |b| {
        b.iter(|| {
            let session = engine.session(SessionOptions::default()).expect("session");
            session
                .generate(path.as_ref(), &mut |_, _| {})
                .expect("generates")
        })
    });
}

criterion_group!(benches, export, script);
criterion_main!(benches);
