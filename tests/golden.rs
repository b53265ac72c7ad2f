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
    lsystems_bush: "scripts/lsystems/bush.lua" => 0x0963e8ae83a1de76,
    lsystems_koch: "scripts/lsystems/koch.lua" => 0x5c19afcd886c5a5f,
    lsystems_plants: "scripts/lsystems/plants.lua" => 0xee201afee1f27595,
    lsystems_signal: "scripts/lsystems/signal.lua" => 0xb0d99be6c6d811a3,
    lsystems_stochastic: "scripts/lsystems/stochastic.lua" => 0x0cf94d362add497e,
    lsystems_hogeweg: "scripts/lsystems/hogeweg.lua" => 0x15be95244926e301,
    lsystems_ternary: "scripts/lsystems/ternary.lua" => 0x1b2160685439858f,
    species_oak: "scripts/species/oak.lua" => 0x25f0911594a9753c,
    species_conifer: "scripts/species/conifer.lua" => 0x0880543fe861d69f,
    species_spruce: "scripts/species/spruce.lua" => 0x3019ac7053047373,
    species_willow: "scripts/species/willow.lua" => 0x1fd245168223e5dd,
    species_topiary: "scripts/species/topiary.lua" => 0xdcd2a4dba356ef88,
    species_vase: "scripts/species/vase.lua" => 0x5a42d5dce9823953,
    species_broadleaf: "scripts/species/broadleaf.lua" => 0x2b33f1f1ea7300e6,
    examples_lod: "scripts/examples/lod.lua" => 0xbcb359a597b82b9c,
    forests_mixed: "scripts/forests/mixed.lua" => 0x898675c0b607fa7d,
    modellers_coral: "scripts/modellers/coral.lua" => 0xeef6617cd7aced4e,
    modellers_crystals: "scripts/modellers/crystals.lua" => 0xfaa82c0ee0d9706d,
    modellers_sierpinski: "scripts/modellers/sierpinski.lua" => 0x0279153693a1c478,
    modellers_fireworks: "scripts/modellers/fireworks.lua" => 0x042203ceaf1f1535,
    modellers_explorers: "scripts/modellers/explorers.lua" => 0xf26527e13ca281d9,
}
