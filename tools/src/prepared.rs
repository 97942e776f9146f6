//! What frames of one process can share: scenes prepared (loaded, their BVH built and
//! staged in main memory's layout) and blocks compiled. `spu paper` runs dozens of frames
//! of the same few scenes and kernels in one process; keeping each scene prepared while
//! frames of it remain saves building the same BVH again (a third of a second for the
//! beetle) for every frame, and one code cache for all of them compiles each block once.
//! The frames' results do not depend on either.

use spu_isa::jit::{CodeCache, Compiling};
use spu_loader::frame::SCENE_BASE;
use spu_loader::{procedural, Bvh, BvhConfig, Scene, StagedScene};
use std::collections::HashMap;
use std::sync::{Arc, Mutex, OnceLock};

/// A scene with the camera a frame asked for, and its staged image.
pub struct PreparedScene {
    pub scene: Scene,
    pub staged: StagedScene,
}

type Cell = Arc<OnceLock<Result<Arc<PreparedScene>, String>>>;

/// Scenes by name and camera option.
type Scenes = HashMap<(String, Option<String>), Cell>;

/// The scenes kept for later frames; `None` while nothing is kept (a single frame).
static KEPT: Mutex<Option<Scenes>> = Mutex::new(None);

/// The code cache of the frames that share one ([`keep`]).
static CODE: Mutex<Option<CodeCache>> = Mutex::new(None);

/// From now on, scenes stay prepared for later frames until [`forget`], and every frame
/// uses one code cache.
pub fn keep() {
    let mut kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
    kept.get_or_insert_with(HashMap::new);
    // The frames keep the host's cores busy themselves: blocks are compiled on the thread
    // of the frame that needs them first, not on a thread of their own.
    *CODE.lock().unwrap_or_else(|e| e.into_inner()) = Some(CodeCache::with(Compiling::Inline));
}

/// The code cache frames share, once [`keep`] was called.
pub fn code() -> Option<CodeCache> {
    CODE.lock().unwrap_or_else(|e| e.into_inner()).clone()
}

/// No later frame needs `scene` (with any camera): its kept preparation goes once the
/// frames using it end.
pub fn forget(scene: &str) {
    let mut kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
    if let Some(map) = kept.as_mut() {
        map.retain(|(name, _), _| name != scene);
    }
}

/// Scene `name` (built-in or a file) with the camera `camera` (already parsed from
/// `camera_option`, the option's text) when given, prepared now or kept from an earlier
/// frame. Two frames asking at once for a scene not prepared yet prepare it once.
pub fn prepare(
    name: &str,
    camera_option: Option<&str>,
    camera: Option<spu_loader::camera::Camera>,
) -> Result<Arc<PreparedScene>, String> {
    let build = || -> Result<Arc<PreparedScene>, String> {
        let mut scene = load_scene(name)?;
        if let Some(camera) = camera {
            scene.camera = camera;
        }
        let bvh = Bvh::build(&scene, &BvhConfig::default());
        let staged = StagedScene::new(&scene, &bvh, SCENE_BASE)?;
        Ok(Arc::new(PreparedScene { scene, staged }))
    };
    let cell = {
        let mut kept = KEPT.lock().unwrap_or_else(|e| e.into_inner());
        match kept.as_mut() {
            None => return build(),
            Some(map) => map
                .entry((name.to_string(), camera_option.map(str::to_string)))
                .or_default()
                .clone(),
        }
    };
    cell.get_or_init(build).clone()
}

/// Loads a built-in scene by name, or a file.
fn load_scene(name: &str) -> Result<Scene, String> {
    if let Some(scene) = procedural::by_name(name) {
        return Ok(scene);
    }
    Scene::load(name).map_err(|e| e.to_string())
}
