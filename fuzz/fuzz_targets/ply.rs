//! The PLY loader never panics or over-allocates, whatever the bytes (ASCII or binary):
//! it loads a scene or returns an error naming the file; a loaded scene stages.
#![no_main]
use libfuzzer_sys::fuzz_target;

include!("scene_common.rs");

fuzz_target!(|data: &[u8]| {
    let path = std::path::Path::new("fuzz.ply");
    match spu_loader::ply::parse_ply(path, data) {
        Ok(scene) => stage(scene),
        Err(e) => assert!(e.to_string().starts_with("fuzz.ply")),
    }
});
