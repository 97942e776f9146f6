//! What a program may reach on the host: its standard streams always, and files only
//! inside the one directory `spu run --root DIR` grants. A path is refused (EACCES) when
//! it is absolute, names `..`, or resolves (through symbolic links) outside the root.

use super::errno;
use std::ffi::OsStr;
use std::os::unix::ffi::OsStrExt;
use std::path::{Component, Path, PathBuf};

#[derive(Clone, Debug, Default)]
pub struct Sandbox {
    /// The granted directory, canonical; `None`: no file may be opened.
    root: Option<PathBuf>,
}

impl Sandbox {
    /// A sandbox granting `root` (which must be a directory), or nothing.
    pub fn new(root: Option<&Path>) -> Result<Sandbox, String> {
        let root = match root {
            None => None,
            Some(r) => {
                let c = r
                    .canonicalize()
                    .map_err(|e| format!("--root {}: {e}", r.display()))?;
                if !c.is_dir() {
                    return Err(format!("--root {}: not a directory", r.display()));
                }
                Some(c)
            }
        };
        Ok(Sandbox { root })
    }

    /// The host path a program's `path` names, or the errno refusing it. `create`: the
    /// file need not exist (its directory must).
    pub fn resolve(&self, path: &[u8]) -> Result<PathBuf, i32> {
        let Some(root) = &self.root else {
            return Err(errno::EACCES);
        };
        if path.is_empty() {
            return Err(errno::ENOENT);
        }
        let rel = Path::new(OsStr::from_bytes(path));
        for c in rel.components() {
            match c {
                Component::Normal(_) | Component::CurDir => {}
                // Absolute paths and `..` are refused before anything is looked up.
                _ => return Err(errno::EACCES),
            }
        }
        let joined = root.join(rel);
        let inside = |p: &Path| p.starts_with(root);
        match joined.canonicalize() {
            Ok(c) if inside(&c) => Ok(c),
            Ok(_) => Err(errno::EACCES),
            Err(_) => {
                // Not there (or a dangling link): its directory must be inside, and the
                // name itself must not be a link.
                if joined.symlink_metadata().is_ok() {
                    return Err(errno::EACCES);
                }
                let name = joined.file_name().ok_or(errno::ENOENT)?;
                let parent = joined.parent().ok_or(errno::ENOENT)?;
                match parent.canonicalize() {
                    Ok(p) if inside(&p) => Ok(p.join(name)),
                    Ok(_) => Err(errno::EACCES),
                    Err(_) => Err(errno::ENOENT),
                }
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn paths_stay_inside_the_root() {
        let dir = std::env::temp_dir().join(format!("spu-sandbox-{}", std::process::id()));
        let root = dir.join("root");
        std::fs::create_dir_all(root.join("sub")).unwrap();
        std::fs::write(dir.join("secret"), b"x").unwrap();
        std::fs::write(root.join("ok"), b"y").unwrap();
        let _ = std::os::unix::fs::symlink(dir.join("secret"), root.join("link"));
        let _ = std::os::unix::fs::symlink("ok", root.join("inner"));
        let s = Sandbox::new(Some(&root)).unwrap();
        let root = root.canonicalize().unwrap();
        assert_eq!(s.resolve(b"ok"), Ok(root.join("ok")));
        assert_eq!(s.resolve(b"./sub/new"), Ok(root.join("sub/new")));
        assert_eq!(s.resolve(b"inner"), Ok(root.join("ok")));
        assert_eq!(s.resolve(b"../secret"), Err(errno::EACCES));
        assert_eq!(s.resolve(b"sub/../ok"), Err(errno::EACCES));
        assert_eq!(
            s.resolve(dir.join("secret").as_os_str().as_bytes()),
            Err(errno::EACCES)
        );
        assert_eq!(s.resolve(b"link"), Err(errno::EACCES));
        assert_eq!(s.resolve(b"nodir/x"), Err(errno::ENOENT));
        assert_eq!(
            Sandbox::new(None).unwrap().resolve(b"ok"),
            Err(errno::EACCES)
        );
        let _ = std::fs::remove_dir_all(&dir);
    }
}
