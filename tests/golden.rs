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
    examples_spiral: "scripts/examples/spiral.lua" => 0xc4a2fb5d5eb02a81,
    examples_terrain: "scripts/examples/terrain.lua" => 0x63bda6c98dfd29bd,
    examples_sky: "scripts/examples/sky.lua" => 0x8e25042e21ed735a,
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x53009a27fba5d706,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x598688156846438e,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x8eca8e5c7ca4f9ca,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0xeca4454a7c4dfac4,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x3a5e8b951361635d,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x0eed5a8d66b96f9d,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x496957f062617314,
    species_oak: "scripts/species/oak.lua" => 0x7402b058a607a586,
    species_conifer: "scripts/species/conifer.lua" => 0xa8025f987ec0b67a,
    species_spruce: "scripts/species/spruce.lua" => 0xd3a88f9327f753cb,
    species_willow: "scripts/species/willow.lua" => 0x6a026bfcd17aafbd,
    species_topiary: "scripts/species/topiary.lua" => 0x84be3ec4e7c329d9,
    species_vase: "scripts/species/vase.lua" => 0x1278b19e92444698,
    species_broadleaf: "scripts/species/broadleaf.lua" => 0x753838d5155f6352,
    examples_lod: "scripts/examples/lod.lua" => 0x0856d0582a7a9553,
    forests_mixed: "scripts/forests/mixed.lua" => 0x6660bfb29c4f36a2,
    modellers_coral: "scripts/modellers/coral.lua" => 0x5c040ab699353163,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0x292480184dda20d1,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
