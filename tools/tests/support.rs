//! What the command-line tests share: a fresh directory per test and `spu` run in it.

use std::path::{Path, PathBuf};
use std::process::Command;

/// A fresh, empty directory for one test: `group` (the test file's) and `test` keep the
/// tests of the one binary, running in parallel, apart.
pub fn fresh_dir(group: &str, test: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("spu-{group}-{}-{test}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// Runs `spu` in `cwd`: stdout, stderr, exit status (-1 for a signal).
pub fn spu_in(args: &[&str], cwd: &Path) -> (String, String, i32) {
    let out = Command::new(env!("CARGO_BIN_EXE_spu"))
        .args(args)
        .current_dir(cwd)
        .output()
        .unwrap();
    (
        String::from_utf8_lossy(&out.stdout).into_owned(),
        String::from_utf8_lossy(&out.stderr).into_owned(),
        out.status.code().unwrap_or(-1),
    )
}
