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
    examples_spiral: "scripts/examples/spiral.lua" => 0xa145e7d268624458,
    examples_terrain: "scripts/examples/terrain.lua" => 0xd4a9e0da68b62718,
    examples_sky: "scripts/examples/sky.lua" => 0xffc5958976bc7255,
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x477a28f75b146a54,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x16d323c547ecf040,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x65eb2d4e50ebabf1,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0x6e9914fc8c5b4d29,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x5c81992c51a02f31,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0xe6d4deabdcc89ce4,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x5aa417d9177285d8,
    species_oak: "scripts/species/oak.lua" => 0xf824a379d79f6770,
    species_conifer: "scripts/species/conifer.lua" => 0xe7c48e263494dcd4,
    species_willow: "scripts/species/willow.lua" => 0xba038b1d09ffd1e1,
    species_topiary: "scripts/species/topiary.lua" => 0xd8bca24316e87b56,
    species_vase: "scripts/species/vase.lua" => 0x7ce0fe3016e1d054,
    modellers_coral: "scripts/modellers/coral.lua" => 0xac5dfa515e0e61fb,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0x3d438d0e8e0d7687,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0xc08a0bbb72f8d1e8,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x58798d5e47af5873,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xfcc24eb4db010825,
}
