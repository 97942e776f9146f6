//! What frames of one process can share: scenes prepared (loaded, their BVH built and
//! staged in main memory's layout) and blocks compiled. `spu paper` runs dozens of frames
//! of the same few scenes and kernels in one process; keeping each scene prepared while
//! frames of it remain saves building the same BVH again (a third of a second for the
//! beetle) for every frame, and one code cache for all of them compiles each block once.
//! The frames' results do not depend on either. `spu paper` owns one [`Kept`] and passes
//! it to its frames; nothing here is process-wide.

use spu_isa::jit::{CodeCache, Compiling};
use spu_loader::render::{prepare_on, Prepared};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

type Cell = Arc<OnceLock<Result<Arc<Prepared>, String>>>;

/// Scenes kept prepared for later frames, by name, and the code cache the frames share.
pub struct Kept {
    scenes: Mutex<HashMap<String, Cell>>,
    /// What each scene prepared so far held ([`Sizes`]), kept after the scene is
    /// forgotten: a moving scene's job is estimated by its still scene.
    sizes: Mutex<HashMap<String, Sizes>>,
    /// Host threads building a BVH (`--threads`: the hierarchy does not depend on it).
    bvh_threads: usize,
    pub code: CodeCache,
}

/// The bytes of a prepared scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Sizes {
    /// Everything it holds: the scene as loaded and as staged, with the host's copies of
    /// the records.
    pub prepared: u64,
    /// The staged image, which each frame copies into its main memory.
    pub image: u64,
}

impl Sizes {
    /// The sizes of `p`, counted from its arrays (their capacity, not their length: what
    /// the allocator holds).
    pub fn of(p: &Prepared) -> Sizes {
        fn bytes<T>(v: &Vec<T>) -> u64 {
            (v.capacity() * std::mem::size_of::<T>()) as u64
        }
        let (scene, staged) = (&p.scene, &p.staged);
        let loaded = bytes(&scene.positions)
            + bytes(&scene.normals)
            + bytes(&scene.texcoords)
            + bytes(&scene.triangles)
            + bytes(&scene.materials)
            + bytes(&scene.lights);
        let records = bytes(&staged.nodes)
            + bytes(&staged.triangles)
            + bytes(&staged.vertices)
            + bytes(&staged.materials);
        Sizes {
            prepared: loaded + records + bytes(&staged.image),
            image: bytes(&staged.image),
        }
    }
}

impl Kept {
    /// Nothing kept yet; scenes' hierarchies built on `bvh_threads` host threads.
    pub fn new(bvh_threads: usize) -> Kept {
        Kept {
            scenes: Mutex::new(HashMap::new()),
            sizes: Mutex::new(HashMap::new()),
            bvh_threads: bvh_threads.max(1),
            // The frames keep the host's cores busy themselves: blocks are compiled on the
            // thread of the frame that needs them first, not on a thread of their own.
            code: CodeCache::with(Compiling::Inline),
        }
    }

    /// Scene `name` (built-in or a file), prepared now or kept from an earlier frame. Two
    /// frames asking at once for a scene not prepared yet prepare it once; `prepared`
    /// hears of each preparation, with its sizes.
    pub fn prepare(
        &self,
        name: &str,
        prepared: impl FnOnce(Sizes),
    ) -> Result<Arc<Prepared>, String> {
        let cell = self
            .scenes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .entry(name.to_string())
            .or_default()
            .clone();
        cell.get_or_init(|| {
            let p = prepare_on(name, self.bvh_threads)?;
            let sizes = Sizes::of(&p);
            self.sizes
                .lock()
                .unwrap_or_else(|e| e.into_inner())
                .insert(name.to_string(), sizes);
            prepared(sizes);
            Ok(Arc::new(p))
        })
        .clone()
    }

    /// The sizes scene `name` had when it was last prepared, if it was.
    pub fn sizes(&self, name: &str) -> Option<Sizes> {
        self.sizes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .get(name)
            .copied()
    }

    /// No later frame needs `scene`: its kept preparation goes once the frames using it
    /// end. Returns its sizes, where it had been prepared.
    pub fn forget(&self, scene: &str) -> Option<Sizes> {
        let cell = self
            .scenes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .remove(scene)?;
        match cell.get() {
            Some(Ok(p)) => Some(Sizes::of(p)),
            _ => None,
        }
    }
}
