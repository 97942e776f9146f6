//! The OBJ loader never panics or over-allocates, whatever the text: it loads a scene or
//! returns an error naming the file; a loaded scene stages.
#![no_main]
use libfuzzer_sys::fuzz_target;

include!("scene_common.rs");

fuzz_target!(|data: &[u8]| {
    // A directory that does not exist, so `mtllib` names resolve to nothing.
    let path = std::path::Path::new("/nonexistent-spu-fuzz/scene.obj");
    match spu_loader::obj::parse_obj(path, data) {
        Ok(scene) => stage(scene),
        Err(e) => assert!(e.to_string().starts_with("/nonexistent-spu-fuzz/scene.obj")),
    }
});
