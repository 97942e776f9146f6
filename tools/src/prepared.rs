//! What frames of one process can share: scenes prepared (loaded, their BVH built and
//! staged in main memory's layout) and blocks compiled. `spu paper` runs dozens of frames
//! of the same few scenes and kernels in one process; keeping each scene prepared while
//! frames of it remain saves building the same BVH again (a third of a second for the
//! beetle) for every frame, and one code cache for all of them compiles each block once.
//! The frames' results do not depend on either. `spu paper` owns one [`Kept`] and passes
//! it to its frames; nothing here is process-wide.

use spu_isa::jit::{CodeCache, Compiling};
use spu_loader::render::{prepare, Prepared};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

type Cell = Arc<OnceLock<Result<Arc<Prepared>, String>>>;

/// Scenes kept prepared for later frames, by name, and the code cache the frames share.
pub struct Kept {
    scenes: Mutex<HashMap<String, Cell>>,
    pub code: CodeCache,
}

impl Default for Kept {
    fn default() -> Self {
        Kept {
            scenes: Mutex::new(HashMap::new()),
            // The frames keep the host's cores busy themselves: blocks are compiled on the
            // thread of the frame that needs them first, not on a thread of their own.
            code: CodeCache::with(Compiling::Inline),
        }
    }
}

impl Kept {
    /// Scene `name` (built-in or a file), prepared now or kept from an earlier frame. Two
    /// frames asking at once for a scene not prepared yet prepare it once.
    pub fn prepare(&self, name: &str) -> Result<Arc<Prepared>, String> {
        let cell = self
            .scenes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .entry(name.to_string())
            .or_default()
            .clone();
        cell.get_or_init(|| prepare(name).map(Arc::new)).clone()
    }

    /// No later frame needs `scene`: its kept preparation goes once the frames using it end.
    pub fn forget(&self, scene: &str) {
        self.scenes
            .lock()
            .unwrap_or_else(|e| e.into_inner())
            .remove(scene);
    }
}
