//! The runs `spu paper` needs: the scenes, and one render configuration
//! ([`RenderConfig`]) per job, named so that its stats file can be found again.

use crate::paper_data::PaperScene;
use crate::render_options::Outputs;
use spu_loader::render::{RenderConfig, Shading};
use spu_loader::shading::ShadeMode;
use std::path::{Path, PathBuf};

/// A scene of the report and the paper column it stands in for.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SceneSpec {
    /// Short name used in `--scenes`, job names and the report.
    pub id: String,
    /// What `spu render --scene` is given: a built-in name or a file path.
    pub render_name: String,
    pub paper: PaperScene,
}

/// The built-in stand-ins for the paper's scenes.
const BUILT_IN: [(&str, PaperScene); 3] = [
    ("room", PaperScene::Erw6),
    ("conference", PaperScene::Conference),
    ("beetle", PaperScene::Beetle),
];

/// The shared public scenes closest to the paper's (see shared/scenes/README.md).
const SHARED: [(&str, &str, PaperScene); 3] = [
    (
        "shared-cornell-suzanne",
        "cornell-suzanne.obj.gz",
        PaperScene::Erw6,
    ),
    (
        "shared-conference",
        "conference.obj.gz",
        PaperScene::Conference,
    ),
    ("shared-dragon", "dragon.ply.gz", PaperScene::Beetle),
];

/// Every scene the report knows, the shared ones where their files are present; and a
/// note for each shared scene that is absent.
pub fn known_scenes(shared_dir: &Path) -> (Vec<SceneSpec>, Vec<String>) {
    let mut scenes: Vec<SceneSpec> = BUILT_IN
        .iter()
        .map(|(id, paper)| SceneSpec {
            id: id.to_string(),
            render_name: id.to_string(),
            paper: *paper,
        })
        .collect();
    let mut notes = Vec::new();
    for (id, file, paper) in SHARED {
        let path = shared_dir.join(file);
        if path.is_file() {
            let path = path.canonicalize().unwrap_or(path);
            scenes.push(SceneSpec {
                id: id.to_string(),
                render_name: path.display().to_string(),
                paper,
            });
        } else {
            notes.push(format!(
                "scene {id} skipped: {} is absent (the shared scenes live beside the project)",
                path.display()
            ));
        }
    }
    (scenes, notes)
}

/// The scenes named in `--scenes` (comma-separated ids), or all known ones.
pub fn select_scenes(
    list: Option<&str>,
    shared_dir: &Path,
) -> Result<(Vec<SceneSpec>, Vec<String>), String> {
    let (known, notes) = known_scenes(shared_dir);
    let Some(list) = list else {
        return Ok((known, notes));
    };
    let mut chosen: Vec<SceneSpec> = Vec::new();
    for id in list.split(',').map(str::trim).filter(|s| !s.is_empty()) {
        match known.iter().find(|s| s.id == id) {
            Some(s) if !chosen.contains(s) => chosen.push(s.clone()),
            Some(_) => {}
            None if SHARED.iter().any(|(sid, _, _)| *sid == id) => {
                return Err(format!(
                    "--scenes: {id} needs its file in {}, which is absent",
                    shared_dir.display()
                ))
            }
            None => {
                let names: Vec<String> = BUILT_IN
                    .iter()
                    .map(|(id, _)| id.to_string())
                    .chain(SHARED.iter().map(|(id, _, _)| id.to_string()))
                    .collect();
                return Err(format!(
                    "--scenes: unknown scene {id:?} (known: {})",
                    names.join(", ")
                ));
            }
        }
    }
    if chosen.is_empty() {
        return Err("--scenes: no scene named".into());
    }
    Ok((chosen, Vec::new()))
}

/// SHT depth of the paper's software hyperthreading runs.
pub const SHT_ON: u32 = 4;

/// One frame of the report.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Job {
    pub scene_id: String,
    pub scene_arg: String,
    pub size: u32,
    pub spes: usize,
    pub clock_mhz: u32,
    /// Lines of both caches.
    pub cache: u32,
    pub assoc: u32,
    pub sht: u32,
    pub shade: &'static str,
    /// The ISA extensions the job's SPUs run with, as `--ext` writes them ("none": the
    /// real SPU, or whatever `spu paper --ext` gives every run).
    pub ext: &'static str,
    /// Frames of a moving scene (`spu render --frames`); 0: one still frame.
    pub frames: u32,
}

/// The settings of a job.
#[derive(Clone, Copy, Debug)]
pub struct Want {
    pub spes: usize,
    pub clock_ghz: f64,
    pub cache: u32,
    pub assoc: u32,
    pub sht: u32,
    pub shade: &'static str,
    pub ext: &'static str,
    /// Frames of a moving scene; 0: one still frame.
    pub frames: u32,
}

impl Default for Want {
    fn default() -> Self {
        Want {
            spes: 1,
            clock_ghz: 2.4,
            cache: 256,
            assoc: 1,
            sht: 1,
            shade: "none",
            ext: "none",
            frames: 0,
        }
    }
}

impl Job {
    /// The job of `scene` at `size` for `want`.
    pub fn new(scene: &SceneSpec, size: u32, want: Want) -> Job {
        Job {
            scene_id: scene.id.clone(),
            scene_arg: scene.render_name.clone(),
            size,
            spes: want.spes,
            clock_mhz: (want.clock_ghz * 1000.0).round() as u32,
            cache: want.cache,
            assoc: want.assoc,
            sht: want.sht,
            shade: want.shade,
            ext: want.ext,
            frames: want.frames,
        }
    }

    /// The frame the job renders, its SPEs simulated on one host thread (the jobs run
    /// side by side).
    pub fn config(&self) -> RenderConfig {
        let mode = ShadeMode::parse(self.shade).unwrap_or(ShadeMode::None);
        let ext = self.extensions();
        RenderConfig {
            width: self.size,
            height: self.size,
            spes: self.spes,
            threads: 1,
            clock_ghz: self.clock_ghz(),
            bvh_cache: self.cache,
            tri_cache: self.cache,
            assoc: self.assoc,
            sht: self.sht,
            shading: Shading {
                mode,
                ..Shading::default()
            },
            kernel: RenderConfig::kernel_with(false, mode, ext),
            extensions: ext,
            event_log: self.draws_heatmap(),
            ..RenderConfig::new(&self.scene_arg)
        }
    }

    /// The job's own ISA extensions (none where `ext` does not parse: the lists are
    /// this program's own).
    pub fn extensions(&self) -> spu_isa::Extensions {
        spu_isa::Extensions::parse(self.ext).unwrap_or(spu_isa::Extensions::NONE)
    }

    /// What the job writes into `dir`: its statistics and image, and the heat maps of the
    /// base configuration.
    pub fn outputs(&self, dir: &Path) -> Outputs {
        Outputs {
            image: self.image_path(dir),
            stats: Some(self.stats_path(dir)),
            heatmap: self.draws_heatmap().then(|| self.heatmap_path(dir)),
            quiet: true,
            ..Outputs::default()
        }
    }

    /// The file stem of the job's outputs: its settings, readable.
    pub fn name(&self) -> String {
        let assoc = if self.assoc == 4 { "4way" } else { "dm" };
        let ext = match self.ext {
            "none" => String::new(),
            list => format!("-{}", list.replace(['=', ','], "")),
        };
        let frames = match self.frames {
            0 => String::new(),
            n => format!("-{n}frames"),
        };
        format!(
            "{}-{}-{}{}-sht{}-{}spe-{}ghz-{}{ext}{frames}",
            self.scene_id,
            self.shade,
            assoc,
            self.cache,
            self.sht,
            self.spes,
            self.clock_ghz(),
            self.size
        )
    }

    pub fn clock_ghz(&self) -> f64 {
        self.clock_mhz as f64 / 1000.0
    }

    /// A short description for the report's configuration column.
    pub fn describe(&self) -> String {
        format!(
            "{}x{}, {} SPE(s) at {} GHz, {} {}-line caches, SHT {}, shading {}",
            self.size,
            self.size,
            self.spes,
            self.clock_ghz(),
            if self.assoc == 4 {
                "4-way"
            } else {
                "direct-mapped"
            },
            self.cache,
            if self.sht == 1 {
                "off".to_string()
            } else {
                self.sht.to_string()
            },
            self.shade
        ) + &match self.ext {
            "none" => String::new(),
            list => format!(", ext {list}"),
        } + &match self.frames {
            0 => String::new(),
            n => format!(
                ", {n} frames of {}, the BVH refitted on the SPEs",
                self.scene_arg
            ),
        }
    }

    /// Whether this run also draws the scene's heat maps: the paper's base configuration
    /// (one 2.4 GHz SPE, 256-line direct-mapped caches, blocking DMA, no shading).
    pub fn draws_heatmap(&self) -> bool {
        self.spes == 1
            && self.clock_mhz == 2400
            && self.cache == 256
            && self.assoc == 1
            && self.sht == 1
            && self.shade == "none"
            && self.ext == "none"
            && self.frames == 0
    }

    /// The cycles heat map (`--heatmap` writes the DMA-wait map beside it).
    pub fn heatmap_path(&self, dir: &Path) -> PathBuf {
        dir.join(format!("{}-heat.png", self.name()))
    }

    pub fn stats_path(&self, dir: &Path) -> PathBuf {
        dir.join(format!("{}.json", self.name()))
    }

    pub fn image_path(&self, dir: &Path) -> PathBuf {
        dir.join(format!("{}.png", self.name()))
    }
}

/// A shell word, quoted where it needs to be.
pub fn shell_word(s: &str) -> String {
    if !s.is_empty()
        && s.chars()
            .all(|c| c.is_ascii_alphanumeric() || "-_./=:,+".contains(c))
    {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', "'\\''"))
    }
}
