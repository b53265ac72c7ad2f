//! The texture budget: one species' full set at 512 px (bark colour, normal and roughness
//! maps, leaf colour, normal and roughness maps) under 40 ms, generated and encoded (bark
//! as JPEG, the default, leaves as PNG).
//! Generation and encoding are timed apart, and together as the budget counts them.
//!
//! Every benchmark is timed twice: in wall time (group `textures`, the budget's measure) and
//! in the CPU time of the whole process (group `textures cpu`: every thread's time on a CPU,
//! from Linux's `/proc/self/task/*/schedstat`), which a loaded machine inflates far less
//! than the wall time. With `RAYON_NUM_THREADS=1` the CPU time is that of one thread; on
//! two cores and a quiet machine the wall time is about half of it.

use criterion::measurement::Measurement;
use criterion::{BenchmarkGroup, Criterion, criterion_group, criterion_main};
use pge_tree::{
    BarkParams, BarkStyle, LeafParams, LeafShape, TextureFormat, bark_maps, bark_set, encode_maps,
    encode_maps_as, leaf_maps, leaf_set,
};
use std::hint::black_box;

#[path = "common/cpu.rs"]
mod cpu;
use cpu::ProcessCpu;

fn bark(style: BarkStyle) -> BarkParams {
    BarkParams {
        style,
        color: [0.2, 0.12, 0.07, 1.0],
        size: 512,
        depth: 1.0,
        format: TextureFormat::Jpeg,
    }
}

const LEAF: LeafParams = LeafParams {
    shape: LeafShape::Lobed,
    size: 512,
    per_card: 1,
};

fn bench_textures(c: &mut Criterion) {
    let mut group = c.benchmark_group("textures");
    group.sample_size(10);
    texture_benches(&mut group);
    group.finish();
}

fn bench_textures_cpu(c: &mut Criterion<ProcessCpu>) {
    let mut group = c.benchmark_group("textures cpu");
    group.sample_size(10);
    texture_benches(&mut group);
    group.finish();
}

/// The benchmarks, the same in wall and CPU time.
fn texture_benches<M: Measurement>(group: &mut BenchmarkGroup<'_, M>) {
    for style in [
        BarkStyle::Furrowed,
        BarkStyle::Plated,
        BarkStyle::Smooth,
        BarkStyle::Fibrous,
        BarkStyle::Scaly,
    ] {
        group.bench_function(format!("generate bark {style:?} 512"), |b| {
            b.iter(|| bark_maps(black_box(&bark(style))))
        });
    }
    for shape in [LeafShape::Lobed, LeafShape::Palmate, LeafShape::Needles] {
        let leaf = LeafParams {
            shape,
            size: 512,
            per_card: 1,
        };
        group.bench_function(format!("generate leaf {shape:?} 512"), |b| {
            b.iter(|| leaf_maps(black_box(&leaf)))
        });
    }
    // Twig cards, as the library's species draw them: several leaves (or needle shoots)
    // a card, generated and encoded (with the cutoff chosen and the colour dilated).
    for (shape, per_card) in [
        (LeafShape::Lobed, 7),
        (LeafShape::Palmate, 6),
        (LeafShape::Needles, 5),
    ] {
        let leaf = LeafParams {
            shape,
            size: 512,
            per_card,
        };
        group.bench_function(
            format!("generate leaf {shape:?} card of {per_card} 512"),
            |b| b.iter(|| leaf_maps(black_box(&leaf))),
        );
        group.bench_function(format!("leaf set {shape:?} card of {per_card} 512"), |b| {
            b.iter(|| leaf_set(black_box(&leaf)).expect("leaf"))
        });
    }
    let bark_px = bark_maps(&bark(BarkStyle::Furrowed));
    let leaf_px = leaf_maps(&LEAF);
    group.bench_function("encode bark 512", |b| {
        b.iter(|| encode_maps("bark", black_box(bark_px.clone())).expect("encodes"))
    });
    group.bench_function("encode bark 512 jpeg", |b| {
        b.iter(|| {
            encode_maps_as("bark", black_box(bark_px.clone()), TextureFormat::Jpeg)
                .expect("encodes")
        })
    });
    group.bench_function("encode leaf 512", |b| {
        b.iter(|| encode_maps("leaf", black_box(leaf_px.clone())).expect("encodes"))
    });
    // The sets main's bench timed, for comparison.
    for style in [BarkStyle::Furrowed, BarkStyle::Plated] {
        group.bench_function(
            format!("species set 512 ({style:?} bark, lobed leaf)"),
            |b| {
                b.iter(|| {
                    let bark = bark_set(black_box(&bark(style))).expect("bark");
                    let leaf = leaf_set(black_box(&LEAF)).expect("leaf");
                    (bark, leaf)
                })
            },
        );
    }
    // Every species of the gallery (scripts/species/) as its script asks: its bark style and
    // leaf shape, and its leaves a card (`perCard`; 1 when the script gives none).
    for (species, style, shape, per_card) in [
        ("oak", BarkStyle::Furrowed, LeafShape::Lobed, 12),
        ("conifer", BarkStyle::Plated, LeafShape::Needles, 1),
        ("spruce", BarkStyle::Scaly, LeafShape::Needles, 1),
        ("willow", BarkStyle::Fibrous, LeafShape::Lanceolate, 12),
        (
            "maple (limbs_and_crown)",
            BarkStyle::Smooth,
            LeafShape::Palmate,
            12,
        ),
        ("bush and poplar", BarkStyle::Smooth, LeafShape::Ovate, 12),
        (
            "broadleaf and five more",
            BarkStyle::Furrowed,
            LeafShape::Ovate,
            12,
        ),
    ] {
        let leaf = LeafParams {
            shape,
            size: 512,
            per_card,
        };
        group.bench_function(format!("species {species} 512"), |b| {
            b.iter(|| {
                let bark = bark_set(black_box(&bark(style))).expect("bark");
                let leaf = leaf_set(black_box(&leaf)).expect("leaf");
                (bark, leaf)
            })
        });
    }
}

criterion_group!(wall, bench_textures);
criterion_group! {
    name = cpu;
    config = Criterion::default().with_measurement(ProcessCpu);
    targets = bench_textures_cpu
}
criterion_main!(wall, cpu);
