//! Foliage that keeps its coverage at every distance: a PNG carries no mipmaps,
//! so every client box-filters its own chain, which ends at the texture's mean alpha. Every
//! alpha-masked material of every script in `scripts/species/` and `scripts/forests/` must
//! have a base-colour texture whose mean alpha (its 1x1 level) is at least its
//! `alphaCutoff + 0.05`, or the leaves vanish at a distance. The oak's cards are at real
//! scale: twigs of leaves of 8-12 cm, cards of at most about 40 cm.

mod common;

use common::pge;

/// How far a card's mean alpha must stay above its cutoff.
const MARGIN: f64 = 0.05;

/// Runs `script` with `args` to a glb and returns its bytes.
fn glb_of(script: &str, args: &[&str]) -> Vec<u8> {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let mut all = vec!["run", script, "-o", out_s.as_str(), "-q"];
    all.extend_from_slice(args);
    let o = pge(&all);
    assert!(
        o.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    std::fs::read(&out).expect("glb written")
}

/// Every alpha-masked material of a glb: its name, cutoff and the mean alpha of its
/// base-colour texture.
fn masked(script: &str, glb: &[u8]) -> Vec<(String, f64, f64)> {
    let (doc, _, images) = gltf::import_slice(glb).unwrap_or_else(|e| panic!("{script}: {e}"));
    doc.materials()
        .filter(|m| m.alpha_mode() == gltf::material::AlphaMode::Mask)
        .map(|m| {
            let name = m.name().unwrap_or("?").to_string();
            let cutoff = f64::from(m.alpha_cutoff().unwrap_or(0.5));
            let texture = m
                .pbr_metallic_roughness()
                .base_color_texture()
                .unwrap_or_else(|| panic!("{script}: {name}: a masked material has a texture"));
            let image = &images[texture.texture().source().index()];
            let mean = match image.format {
                gltf::image::Format::R8G8B8A8 => {
                    let sum: u64 = image.pixels.chunks_exact(4).map(|p| u64::from(p[3])).sum();
                    sum as f64 / (255.0 * (image.pixels.len() / 4) as f64)
                }
                gltf::image::Format::R8G8B8 | gltf::image::Format::R8 => 1.0,
                other => panic!("{script}: {name}: texture format {other:?}"),
            };
            (name, cutoff, mean)
        })
        .collect()
}

/// Asserts the coverage rule on every masked material of `script` run with `args`.
fn check(script: &str, args: &[&str]) {
    let glb = glb_of(script, args);
    let materials = masked(script, &glb);
    for (name, cutoff, mean) in &materials {
        assert!(
            *mean >= cutoff + MARGIN,
            "{script}: material '{name}': mean alpha {mean:.3} under alphaCutoff {cutoff} + \
             {MARGIN}: a client's own mipmaps lose it at a distance"
        );
    }
}

macro_rules! foliage {
    ($($name:ident: $script:expr $(, $arg:expr)*;)*) => {
        $(
            #[test]
            fn $name() {
                check($script, &[$($arg),*]);
            }
        )*

        /// The scripts the tests above run.
        const CHECKED: &[&str] = &[$($script),*];
    };
}

foliage! {
    species_bonsai: "scripts/species/bonsai.lua";
    species_broadleaf: "scripts/species/broadleaf.lua";
    species_bush: "scripts/species/bush.lua";
    species_conifer: "scripts/species/conifer.lua";
    species_limbs_and_crown: "scripts/species/limbs_and_crown.lua";
    species_oak: "scripts/species/oak.lua";
    species_poplar: "scripts/species/poplar.lua";
    species_spruce: "scripts/species/spruce.lua";
    species_topiary: "scripts/species/topiary.lua";
    species_vase: "scripts/species/vase.lua";
    species_willow: "scripts/species/willow.lua";
    species_young_then_colonized: "scripts/species/young_then_colonized.lua";
    forests_big: "scripts/forests/big.lua", "--set", "points=200", "--set", "variants=1",
        "--tile", "1,1";
    forests_mixed: "scripts/forests/mixed.lua", "--set", "points=300", "--set", "size=120",
        "--set", "variants=1";
    forests_painted: "scripts/forests/painted.lua", "--set", "points=300";
    forests_plantation: "scripts/forests/plantation.lua", "--set", "points=300";
    // The LOD atlas of leaf clusters (lod = {atlas = true}) chooses its own cutoff.
    examples_lod_atlas: "scripts/examples/lod.lua", "--set", "points=600", "--set", "atlas=1";
}

#[test]
fn every_species_and_forest_script_is_checked() {
    for dir in ["scripts/species", "scripts/forests"] {
        let entries = std::fs::read_dir(common::root().join(dir)).expect("scripts");
        for entry in entries {
            let path = entry.expect("entry").path();
            if path.extension().and_then(|e| e.to_str()) != Some("lua") {
                continue;
            }
            let name = path.file_name().and_then(|n| n.to_str()).expect("name");
            let script = format!("{dir}/{name}");
            assert!(
                CHECKED.contains(&script.as_str()),
                "{script} is not checked for foliage coverage: add it to foliage! above"
            );
        }
    }
}

/// The leaf mesh's cards (quads, four vertices each): their lengths (stalk edge to far
/// edge), metres.
fn card_lengths(glb: &[u8]) -> Vec<f32> {
    let (doc, buffers, _) = gltf::import_slice(glb).expect("glb");
    let mut lengths = Vec::new();
    for mesh in doc.meshes() {
        for prim in mesh.primitives() {
            if prim.material().alpha_mode() != gltf::material::AlphaMode::Mask {
                continue;
            }
            let reader = prim.reader(|b| buffers.get(b.index()).map(|d| &d.0[..]));
            let p: Vec<[f32; 3]> = reader.read_positions().expect("positions").collect();
            for q in p.chunks_exact(4) {
                let d = [0, 1, 2].map(|k| q[3][k] - q[0][k]);
                lengths.push((d[0] * d[0] + d[1] * d[1] + d[2] * d[2]).sqrt());
            }
        }
    }
    lengths
}

#[test]
fn oak_cards_are_twigs_of_leaves_at_real_scale() {
    let glb = glb_of("scripts/species/oak.lua", &[]);
    let mut lengths = card_lengths(&glb);
    assert!(lengths.len() > 1000, "{} cards", lengths.len());
    lengths.sort_by(f32::total_cmp);
    let median = lengths[lengths.len() / 2];
    let longest = lengths[lengths.len() - 1];
    // Twig cards of 8-12 cm oak leaves: about 20-30 cm, none over about 40 cm (a card of one
    // leaf 0.38 m long was three times a real oak leaf).
    assert!((0.15..=0.35).contains(&median), "median card {median} m");
    assert!(longest <= 0.42, "longest card {longest} m");
    // The leaves on them: the card's length times the leaf's share of it.
    let source =
        std::fs::read_to_string(common::root().join("scripts/species/oak.lua")).expect("oak.lua");
    let per_card: u32 = source
        .split("perCard = ")
        .nth(1)
        .and_then(|s| s.split(|c: char| !c.is_ascii_digit()).next())
        .and_then(|n| n.parse().ok())
        .expect("oak.lua sets perCard");
    let leaf = median * pge_tree::card_share(per_card);
    assert!((0.08..=0.12).contains(&leaf), "median leaf {leaf} m");
}
