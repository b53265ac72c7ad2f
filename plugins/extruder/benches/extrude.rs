//! Extruding and meshing: 1000 bent, tapered tubes of 16-gon rings (20 rings each), with flat
//! and smooth normals; and a 10-level Sierpinski-like recursion of prisms.

use criterion::{Criterion, criterion_group, criterion_main};
use glam::Vec3;
use pge_engine::math;
use pge_extruder::{Extruder, ExtruderOptions};

fn tubes(smooth: bool) -> Extruder {
    let mut e = Extruder::new(ExtruderOptions {
        smooth,
        ..ExtruderOptions::default()
    });
    e.set_polygon(16, 0.2).expect("valid polygon");
    for i in 0..1000 {
        e.push().expect("within depth");
        e.path_mut()
            .translate(Vec3::new((i % 32) as f32, 0.0, (i / 32) as f32))
            .expect("finite");
        for _ in 0..19 {
            e.extrude(0.1).expect("extrudes");
            e.path_mut().rotate_z(3.0).expect("finite");
            e.shape_matrix_mut()
                .scale(Vec3::splat(0.98))
                .expect("finite");
        }
        e.pop().expect("pushed");
    }
    e
}

fn prisms(e: &mut Extruder, level: u32) {
    e.push().expect("within depth");
    e.extrude(0.5).expect("extrudes");
    if level > 0 {
        for k in 0..3 {
            e.push().expect("within depth");
            let a = (90.0 + 120.0 * k as f32).to_radians();
            e.path_mut()
                .translate(Vec3::new(0.5 * math::cos(a), 0.0, -0.5 * math::sin(a)))
                .expect("finite");
            e.path_mut().scale(Vec3::splat(0.5)).expect("finite");
            prisms(e, level - 1);
            e.pop().expect("pushed");
        }
    }
    e.pop().expect("pushed");
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("extruder");
    group.sample_size(20);
    group.bench_function("1000_tubes_build_flat", |b| b.iter(|| tubes(false)));
    let flat = tubes(false);
    group.bench_function("1000_tubes_mesh_flat", |b| b.iter(|| flat.mesh()));
    let smooth = tubes(true);
    group.bench_function("1000_tubes_mesh_smooth", |b| b.iter(|| smooth.mesh()));
    group.bench_function("sierpinski_depth_7_build_and_mesh", |b| {
        b.iter(|| {
            let mut e = Extruder::new(ExtruderOptions::default());
            e.set_polygon(3, 10.0).expect("valid polygon");
            prisms(&mut e, 7);
            e.mesh()
        })
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
