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
    examples_spiral: "scripts/examples/spiral.lua" => 0xd9226e7c8cddd1cd,
    examples_terrain: "scripts/examples/terrain.lua" => 0x908e111904f8fb8e,
    examples_sky: "scripts/examples/sky.lua" => 0x732e04af6b49e814,
    lsystems_bush: "scripts/lsystems/bush.lua" => 0xdbd85d6a80eedeec,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x822c968a13e0f950,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x16b9d9b943a65fd3,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0x0dc64f18209a57a4,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x7fdcbce1e6df6a95,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x1bf65e113b812a8a,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x9c7c595aae9da22a,
    species_oak: "scripts/species/oak.lua" => 0x2c9f170281c5ec1f,
    species_conifer: "scripts/species/conifer.lua" => 0xceefb7708804314f,
    species_willow: "scripts/species/willow.lua" => 0x40a692f810809f1e,
    species_topiary: "scripts/species/topiary.lua" => 0x645c8b4d1fdb75a6,
    species_vase: "scripts/species/vase.lua" => 0xacc4f08a3edf8500,
    modellers_coral: "scripts/modellers/coral.lua" => 0x544da883c394d1f2,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0x00cba59d321fe9ca,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0xd69cbc44593e397a,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x41fbff946d29bc17,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xb86868b079b284a9,
}
