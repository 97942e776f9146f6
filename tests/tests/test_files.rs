//! Each crate's integration tests are modules of one binary (`CRATE/tests/all.rs`, with
//! `autotests = false`), so a test file that `all.rs` does not name would never build or
//! run. This checks that every `.rs` file in each crate's `tests/` is named there.

use std::collections::BTreeSet;
use std::path::Path;

const CRATES: [&str; 5] = ["isa", "asm", "loader", "tools", "tests"];

/// The `mod NAME;` lines of an `all.rs`.
fn declared_modules(all_rs: &str) -> BTreeSet<String> {
    all_rs
        .lines()
        .filter_map(|line| line.trim().strip_prefix("mod ")?.strip_suffix(';'))
        .map(str::to_string)
        .collect()
}

#[test]
fn every_test_file_is_a_module_of_its_crates_test_binary() {
    let workspace = Path::new(env!("CARGO_MANIFEST_DIR")).join("..");
    for krate in CRATES {
        let dir = workspace.join(krate).join("tests");
        let all_rs = std::fs::read_to_string(dir.join("all.rs"))
            .unwrap_or_else(|e| panic!("{krate}/tests/all.rs: {e}"));
        let declared = declared_modules(&all_rs);
        let files: BTreeSet<String> = std::fs::read_dir(&dir)
            .unwrap_or_else(|e| panic!("{}: {e}", dir.display()))
            .map(|entry| entry.expect("a directory entry").path())
            .filter(|path| path.extension().is_some_and(|e| e == "rs"))
            .filter_map(|path| Some(path.file_stem()?.to_str()?.to_string()))
            .filter(|stem| stem != "all")
            .collect();
        let missing: Vec<_> = files.difference(&declared).collect();
        let stale: Vec<_> = declared.difference(&files).collect();
        assert!(
            missing.is_empty() && stale.is_empty(),
            "{krate}/tests/all.rs: files not declared as modules {missing:?}, \
             modules without a file {stale:?}"
        );
    }
}

#[test]
fn the_module_list_is_read_from_mod_lines() {
    let declared = declared_modules("//! doc\n\nmod a;\nmod b_c;\nfn x() {}\n");
    assert_eq!(declared, BTreeSet::from(["a".into(), "b_c".into()]));
}
