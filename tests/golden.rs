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
    examples_spiral: "scripts/examples/spiral.lua" => 0xfcf7d90e7f7b7ff9,
    examples_terrain: "scripts/examples/terrain.lua" => 0x63bda6c98dfd29bd,
    examples_sky: "scripts/examples/sky.lua" => 0xb93fe4e594da7a1f,
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x88bead5046c70814,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x1c3a0aa8bf0930b0,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x47419d2c845e5290,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0x7e70cf6a170cb11d,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x2cab7c5c0dcc22d9,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0xc7cc265768c01ba2,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x707c3ad7b6e00264,
    species_oak: "scripts/species/oak.lua" => 0xe0aaf8de6ae45766,
    species_conifer: "scripts/species/conifer.lua" => 0xa5bb81b66e880dd1,
    species_spruce: "scripts/species/spruce.lua" => 0x91c1f857bdea155c,
    species_willow: "scripts/species/willow.lua" => 0x3819815785ca9a5f,
    species_topiary: "scripts/species/topiary.lua" => 0xfa6ae0d131b27402,
    species_vase: "scripts/species/vase.lua" => 0x3cce0ed61de5f1fa,
    species_broadleaf: "scripts/species/broadleaf.lua" => 0x3019bfb9851252fe,
    examples_lod: "scripts/examples/lod.lua" => 0x167c6d7778dd92e8,
    forests_mixed: "scripts/forests/mixed.lua" => 0x03834f426d4cb37e,
    modellers_coral: "scripts/modellers/coral.lua" => 0x5c040ab699353163,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0x292480184dda20d1,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
