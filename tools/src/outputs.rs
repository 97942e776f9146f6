//! What a command reads and what it writes, declared before any work starts, so that no
//! output overwrites an input or another output of the same command (`spu as c.s -o c.s`,
//! `render -o s.png --stats s.png`). Paths are compared as the files they name: through
//! symbolic links, hard links by device and inode, and an output that does not exist yet
//! by the directory it would be made in and its name.

use crate::exit::{self, Error};
use std::ffi::OsString;
use std::path::{Path, PathBuf};

/// The files of one command run: each with what names it (`-o`, `--stats`, `the input`).
#[derive(Default)]
pub struct Files {
    inputs: Vec<(String, PathBuf)>,
    outputs: Vec<(String, PathBuf)>,
}

impl Files {
    pub fn new() -> Files {
        Files::default()
    }

    /// A file the command reads; `what` names it in a refusal (`the input`, `--names`).
    pub fn input(&mut self, what: impl Into<String>, path: &Path) -> &mut Files {
        self.inputs.push((what.into(), path.to_path_buf()));
        self
    }

    /// A file the command writes; `option` names it in a refusal (`-o`, `--stats`).
    pub fn output(&mut self, option: impl Into<String>, path: &Path) -> &mut Files {
        self.outputs.push((option.into(), path.to_path_buf()));
        self
    }

    /// Refuses (status 2, naming both) an output that is an input or another output, then
    /// checks that every output can be written ([`exit::check_writable`]).
    pub fn check(&self) -> exit::Result<()> {
        let inputs: Vec<_> = self
            .inputs
            .iter()
            .filter_map(|(what, path)| Some((what, path, identity(path)?)))
            .collect();
        let mut earlier: Vec<(&String, &PathBuf, Identity)> = Vec::new();
        for (option, path) in &self.outputs {
            let Some(id) = identity(path) else {
                continue;
            };
            if let Some((what, input, _)) = inputs.iter().find(|(_, _, other)| *other == id) {
                return Err(Error::input(format!(
                    "{option} {}: would overwrite {what} {}",
                    path.display(),
                    input.display()
                )));
            }
            if let Some((other, first, _)) = earlier.iter().find(|(_, _, other)| *other == id) {
                return Err(Error::input(format!(
                    "{other} {} and {option} {} are the same file: each output needs its own",
                    first.display(),
                    path.display()
                )));
            }
            earlier.push((option, path, id));
        }
        for (_, path) in &self.outputs {
            exit::check_writable(path)?;
        }
        Ok(())
    }
}

/// The file a path names, for comparison.
#[derive(Debug, PartialEq)]
enum Identity {
    /// An existing regular file.
    File { device: u64, inode: u64 },
    /// A file not made yet: where it would be made.
    New {
        device: u64,
        inode: u64,
        name: OsString,
    },
}

/// What `path` names; `None` for what is never replaced or cannot be compared: a device or
/// a pipe (`-o /dev/null` twice is fine), a directory, a path whose directory is missing
/// (the checks of the inputs and outputs themselves report those).
fn identity(path: &Path) -> Option<Identity> {
    match std::fs::metadata(path) {
        Ok(meta) if meta.is_file() => {
            let (device, inode) = device_inode(&meta);
            Some(Identity::File { device, inode })
        }
        Ok(_) => None,
        Err(_) => {
            let target = resolve_links(path);
            let name = target.file_name()?.to_os_string();
            let dir = match target.parent() {
                Some(d) if !d.as_os_str().is_empty() => d,
                _ => Path::new("."),
            };
            let (device, inode) = device_inode(&std::fs::metadata(dir).ok()?);
            Some(Identity::New {
                device,
                inode,
                name,
            })
        }
    }
}

#[cfg(unix)]
fn device_inode(meta: &std::fs::Metadata) -> (u64, u64) {
    use std::os::unix::fs::MetadataExt;
    (meta.dev(), meta.ino())
}

#[cfg(not(unix))]
fn device_inode(_meta: &std::fs::Metadata) -> (u64, u64) {
    (0, 0)
}

/// The material libraries an OBJ scene names (`mtllib NAME`, the rest of the line one
/// name, as `tobj` reads it), where the loader finds them (beside the scene, as named or
/// with `.gz`): inputs of a render, as the scene is. A scene that cannot be read, or is
/// not OBJ, names none here; loading it says why.
pub fn material_libraries(scene: &Path) -> Vec<PathBuf> {
    let name = scene
        .file_name()
        .map(|n| n.to_string_lossy().to_lowercase())
        .unwrap_or_default();
    if !name.trim_end_matches(".gz").ends_with(".obj") {
        return Vec::new();
    }
    let Ok(bytes) = spu_loader::scene::read_maybe_gzipped(scene) else {
        return Vec::new();
    };
    let dir = scene.parent().unwrap_or(Path::new(""));
    let mut found = Vec::new();
    for line in String::from_utf8_lossy(&bytes).lines() {
        let line = line.split('#').next().unwrap_or("").trim();
        let Some(("mtllib", library)) = line.split_once(' ') else {
            continue;
        };
        let plain = dir.join(library.trim());
        let mut gz = plain.clone().into_os_string();
        gz.push(".gz");
        let path = [plain, PathBuf::from(gz)].into_iter().find(|p| p.is_file());
        if let Some(path) = path.filter(|p| !found.contains(p)) {
            found.push(path);
        }
    }
    found
}

/// `path` with its last component's symbolic links followed (a dangling one too: writing
/// to it makes the file it names). A loop stops after 40 links, as the kernel does.
pub fn resolve_links(path: &Path) -> PathBuf {
    let mut path = path.to_path_buf();
    for _ in 0..40 {
        let is_link = std::fs::symlink_metadata(&path).is_ok_and(|m| m.file_type().is_symlink());
        let Some(target) = is_link.then(|| std::fs::read_link(&path).ok()).flatten() else {
            break;
        };
        path = match path.parent() {
            Some(dir) if target.is_relative() => dir.join(target),
            _ => target,
        };
    }
    path
}

#[cfg(test)]
mod tests {
    use super::*;

    fn dir(name: &str) -> PathBuf {
        let d = std::env::temp_dir().join(format!("spu-outputs-{name}-{}", std::process::id()));
        std::fs::create_dir_all(&d).unwrap();
        d
    }

    fn refusal(files: &Files) -> String {
        let e = files.check().unwrap_err();
        assert_eq!(e.status, exit::Status::BadInput);
        e.message.unwrap()
    }

    #[test]
    fn an_output_onto_an_input_is_refused_by_name_link_and_spelling() {
        let d = dir("inputs");
        let src = d.join("c.s");
        std::fs::write(&src, "x").unwrap();
        let mut files = Files::new();
        files.input("the input", &src).output("-o", &src);
        let src_name = src.display();
        assert_eq!(
            refusal(&files),
            format!("-o {src_name}: would overwrite the input {src_name}")
        );
        // another spelling of the same path
        let dotted = d.join(".").join("c.s");
        let mut files = Files::new();
        files.input("the input", &src).output("-o", &dotted);
        assert!(refusal(&files).contains("would overwrite the input"));
        #[cfg(unix)]
        {
            let hard = d.join("hard.s");
            let _ = std::fs::remove_file(&hard);
            std::fs::hard_link(&src, &hard).unwrap();
            let soft = d.join("soft.s");
            let _ = std::fs::remove_file(&soft);
            std::os::unix::fs::symlink("c.s", &soft).unwrap();
            for link in [&hard, &soft] {
                let mut files = Files::new();
                files.input("the input", &src).output("-o", link);
                assert_eq!(
                    refusal(&files),
                    format!(
                        "-o {}: would overwrite the input {src_name}",
                        link.display()
                    )
                );
            }
        }
        // a different file is fine, and the input is left alone
        let mut files = Files::new();
        files.input("the input", &src).output("-o", &d.join("c.o"));
        files.check().unwrap();
        assert_eq!(std::fs::read(&src).unwrap(), b"x");
    }

    #[test]
    fn two_outputs_onto_one_new_file_are_refused() {
        let d = dir("new");
        let a = d.join("s.png");
        let _ = std::fs::remove_file(&a);
        let mut files = Files::new();
        files
            .output("-o", &a)
            .output("--stats", &d.join("sub/../s.png"));
        std::fs::create_dir_all(d.join("sub")).unwrap();
        assert_eq!(
            refusal(&files),
            format!(
                "-o {} and --stats {} are the same file: each output needs its own",
                a.display(),
                d.join("sub/../s.png").display()
            )
        );
        #[cfg(unix)]
        {
            // a dangling link is where the file would be made
            let link = d.join("dangling.png");
            let _ = std::fs::remove_file(&link);
            std::os::unix::fs::symlink("s.png", &link).unwrap();
            let mut files = Files::new();
            files.output("-o", &a).output("--heatmap", &link);
            assert!(refusal(&files).contains("are the same file"));
        }
        // devices are written in place, never replaced: twice is fine
        if Path::new("/dev/null").exists() {
            let mut files = Files::new();
            files
                .output("-o", Path::new("/dev/null"))
                .output("--stats", Path::new("/dev/null"));
            files.check().unwrap();
        }
    }
}
