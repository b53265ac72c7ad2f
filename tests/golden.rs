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
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x53009a27fba5d706,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x598688156846438e,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0x8eca8e5c7ca4f9ca,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0xeca4454a7c4dfac4,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x3a5e8b951361635d,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x0eed5a8d66b96f9d,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x582d812280b73310,
    species_oak: "scripts/species/oak.lua" => 0x164649d1d0733cc1,
    species_conifer: "scripts/species/conifer.lua" => 0x5af40d442d6b992d,
    species_spruce: "scripts/species/spruce.lua" => 0x0a9c1dd773ac095b,
    species_willow: "scripts/species/willow.lua" => 0x4cecffae51c2fd24,
    species_topiary: "scripts/species/topiary.lua" => 0x3dc1c724dfb0fa8f,
    species_vase: "scripts/species/vase.lua" => 0x42bdca9faad24641,
    species_broadleaf: "scripts/species/broadleaf.lua" => 0xa5ba84290d773742,
    examples_lod: "scripts/examples/lod.lua" => 0x4b918c1ebbcdb730,
    forests_mixed: "scripts/forests/mixed.lua" => 0x6a4973c7d8cf04d8,
    modellers_coral: "scripts/modellers/coral.lua" => 0xeef6617cd7aced4e,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0xfaa82c0ee0d9706d,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
