//! Inputs the fuzz targets (`fuzz/fuzz_targets/{ply,obj}.rs`) found crashing the loaders,
//! kept with the error each must now give.

use spu_loader::{obj, ply};
use std::path::Path;

fn input(name: &str) -> Vec<u8> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fuzz_regressions");
    std::fs::read(dir.join(name)).unwrap()
}

/// (file, line, reason) of the error each input must give.
const PLY: &[(&str, Option<usize>, &str)] = &[
    // A second `vertex` element with more properties than the first indexed past the
    // property slots of the first.
    (
        "ply-vertex-element-twice.ply",
        Some(9),
        "element 'vertex' declared twice",
    ),
];

const OBJ: &[(&str, Option<usize>, &str)] = &[];

#[test]
fn ply_regressions_give_their_errors() {
    for &(name, line, reason) in PLY {
        let err = ply::parse_ply(Path::new(name), &input(name)).unwrap_err();
        assert_eq!((err.line, err.reason.as_str()), (line, reason), "{name}");
    }
}

#[test]
fn obj_regressions_give_their_errors() {
    for &(name, line, reason) in OBJ {
        let err = obj::parse_obj(Path::new(name), &input(name)).unwrap_err();
        assert_eq!((err.line, err.reason.as_str()), (line, reason), "{name}");
    }
}
