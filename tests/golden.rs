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
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x67979de3c53c74d1,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x99edc6e46f5305f8,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x30dc0d8461ef5c65,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0xa9125809ad152dbb,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x12810713696facf8,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x3a85b8d5481d80b2,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0xc2f6c57cd3c6a8cc,
    species_oak: "scripts/species/oak.lua" => 0x91cb8d569d59117b,
    species_conifer: "scripts/species/conifer.lua" => 0x6c0298bb40d742c4,
    species_spruce: "scripts/species/spruce.lua" => 0x27a7880bd4369699,
    species_willow: "scripts/species/willow.lua" => 0xb96709c7fb833993,
    species_topiary: "scripts/species/topiary.lua" => 0x8350d579869dba30,
    species_vase: "scripts/species/vase.lua" => 0x1c2d9c6bba4abf62,
    modellers_coral: "scripts/modellers/coral.lua" => 0xeef6617cd7aced4e,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0xfaa82c0ee0d9706d,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
