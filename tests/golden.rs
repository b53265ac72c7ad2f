//! Golden outputs: the glb bytes of library scripts, pinned by hash.
//!
//! Refactors and optimisations must not change what a script makes. Each case runs
//! `pge run` on a library script with the default seed and compares a 64-bit FNV-1a hash of
//! the glb with the one recorded. A change that alters output on purpose (a new float
//! summation order, a new feature in the file) updates the hash in the same commit and says
//! why in its message.

mod common;

use common::pge;

/// 64-bit FNV-1a: small, stable across Rust versions and platforms.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h ^= u64::from(*b);
        h = h.wrapping_mul(0x0100_0000_01b3);
    }
    h
}

fn glb_hash(script: &str) -> u64 {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("out.glb");
    let out_s = out.to_string_lossy().to_string();
    let o = pge(&["run", script, "-o", &out_s, "-q"]);
    assert!(
        o.status.success(),
        "{script}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    fnv1a(&std::fs::read(&out).expect("output written"))
}

macro_rules! golden {
    ($($name:ident: $script:expr => $hash:expr,)*) => {
        $(
            #[test]
            fn $name() {
                let got = glb_hash($script);
                assert_eq!(got, $hash, "{}: glb hash is {got:#018x}", $script);
            }
        )*
    };
}

golden! {
    examples_spiral: "scripts/examples/spiral.lua" => 0x50acda51ba7f7b4f,
    examples_terrain: "scripts/examples/terrain.lua" => 0x63bda6c98dfd29bd,
    examples_sky: "scripts/examples/sky.lua" => 0xa26916ad21c9ceca,
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x579ae7683c031ab5,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x176eef56573df236,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0xd65f76d4162c4ad4,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0x7e70cf6a170cb11d,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0xef50235ac05f36c5,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x4043bfb5988ec13a,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x41f9e3b8fb3fd867,
    species_oak: "scripts/species/oak.lua" => 0xf984ffe7f7575efd,
    species_conifer: "scripts/species/conifer.lua" => 0x191266f0632fa3b7,
    species_spruce: "scripts/species/spruce.lua" => 0x499003ae4e6bcb67,
    species_willow: "scripts/species/willow.lua" => 0x1f4f8152c40fa583,
    species_topiary: "scripts/species/topiary.lua" => 0x6f16736e8ea63205,
    species_vase: "scripts/species/vase.lua" => 0xbbdb3fd856faf487,
    species_broadleaf: "scripts/species/broadleaf.lua" => 0x4b614cc7791a509b,
    examples_lod: "scripts/examples/lod.lua" => 0x35ec9d912dbc84da,
    forests_mixed: "scripts/forests/mixed.lua" => 0xff95256955b03506,
    modellers_coral: "scripts/modellers/coral.lua" => 0xeef6617cd7aced4e,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0xfaa82c0ee0d9706d,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
