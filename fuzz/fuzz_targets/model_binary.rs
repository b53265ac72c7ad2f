//! A model's binary form (`pge_engine::geometry::binary`, the forest's variant cache): any
//! bytes decode to a model or a typed error, never a panic, and what decodes encodes to
//! bytes that decode to the same encoding.
#![no_main]

use libfuzzer_sys::fuzz_target;
use pge_engine::geometry::binary::{decode, encode};

fuzz_target!(|bytes: &[u8]| {
    let Ok(model) = decode(bytes) else {
        return;
    };
    let again = encode(&model).expect("a decoded model encodes");
    let back = decode(&again).expect("an encoded model decodes");
    assert_eq!(encode(&back).expect("encodes"), again);
    let _ = (model.vertex_count(), model.triangle_count(), model.bounds());
});
