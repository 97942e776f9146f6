// Shared by the scene-loader targets (included, not a module of its own crate).

/// A loaded scene that passes the loader's checks is staged like `spu render` stages it:
/// the BVH and the big-endian records must build without a panic either.
fn stage(scene: spu_loader::Scene) {
    if scene.check_loaded().is_err() {
        return;
    }
    let bvh = spu_loader::Bvh::build(&scene, &spu_loader::BvhConfig::default());
    let _ = spu_loader::StagedScene::new(&scene, &bvh, spu_loader::frame::SCENE_BASE);
}
