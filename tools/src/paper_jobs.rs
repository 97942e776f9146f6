//! The runs `spu paper` needs: the scenes, what `spu render` can do in this build, and one
//! render configuration per job, named so that its stats file can be found again.

use crate::paper_data::PaperScene;
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

/// What this build's `spu render` can do beyond the blocking direct-mapped ray caster,
/// read from its own options, so the paper's other configurations switch on by
/// themselves when the kernels that need them land.
#[derive(Clone, Copy, Debug, Default)]
pub struct Caps {
    /// `--assoc 1|4`: 4-way set-associative caches.
    pub assoc: bool,
    /// `--sht N`: software hyperthreading.
    pub sht: bool,
    /// `--shade none|simple|shadows`.
    pub shade: bool,
}

impl Caps {
    pub fn of_render() -> Self {
        let cmd = <crate::cmd_render::Args as clap::Args>::augment_args(clap::Command::new("r"));
        let has = |long: &str| cmd.get_arguments().any(|a| a.get_long() == Some(long));
        Caps {
            assoc: has("assoc"),
            sht: has("sht"),
            shade: has("shade"),
        }
    }
}

/// SHT depth of the paper's software hyperthreading runs.
pub const SHT_ON: u32 = 4;

/// One `spu render` run.
#[derive(Clone, Debug, PartialEq, Eq, PartialOrd, Ord, Hash)]
pub struct Job {
    pub scene_id: String,
    pub scene_arg: String,
    pub size: u32,
    pub spes: usize,
    pub clock_mhz: u32,
    /// Lines of both caches.
    pub cache: u32,
    /// `--assoc`, passed only where the option exists.
    pub assoc: Option<u32>,
    /// `--sht`, passed only where the option exists.
    pub sht: Option<u32>,
    /// `--shade`, passed only where the option exists.
    pub shade: Option<&'static str>,
}

/// The settings of a job before they are checked against [`Caps`].
#[derive(Clone, Copy, Debug)]
pub struct Want {
    pub spes: usize,
    pub clock_ghz: f64,
    pub cache: u32,
    pub assoc: u32,
    pub sht: u32,
    pub shade: &'static str,
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
        }
    }
}

impl Job {
    /// The job for `want`, or why this build cannot run it.
    pub fn new(scene: &SceneSpec, size: u32, want: Want, caps: Caps) -> Result<Job, String> {
        if want.assoc != 1 && !caps.assoc {
            return Err("needs 4-way caches (`spu render --assoc 4`), not built yet".into());
        }
        if want.sht != 1 && !caps.sht {
            return Err(
                "needs software hyperthreading (`spu render --sht N`), not built yet".into(),
            );
        }
        if want.shade != "none" && !caps.shade {
            return Err(format!(
                "needs shading (`spu render --shade {}`), not built yet",
                want.shade
            ));
        }
        Ok(Job {
            scene_id: scene.id.clone(),
            scene_arg: scene.render_name.clone(),
            size,
            spes: want.spes,
            clock_mhz: (want.clock_ghz * 1000.0).round() as u32,
            cache: want.cache,
            assoc: caps.assoc.then_some(want.assoc),
            sht: caps.sht.then_some(want.sht),
            shade: caps.shade.then_some(want.shade),
        })
    }

    /// The file stem of the job's outputs: its settings, readable.
    pub fn name(&self) -> String {
        let assoc = if self.assoc.unwrap_or(1) == 4 {
            "4way"
        } else {
            "dm"
        };
        format!(
            "{}-{}-{}{}-sht{}-{}spe-{}ghz-{}",
            self.scene_id,
            self.shade.unwrap_or("none"),
            assoc,
            self.cache,
            self.sht.unwrap_or(1),
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
            if self.assoc.unwrap_or(1) == 4 {
                "4-way"
            } else {
                "direct-mapped"
            },
            self.cache,
            self.sht.map_or("off".to_string(), |n| {
                if n == 1 {
                    "off".into()
                } else {
                    n.to_string()
                }
            }),
            self.shade.unwrap_or("none")
        )
    }

    /// `spu render` arguments (after `render`) writing the stats and image into `dir`.
    pub fn render_args(&self, dir: &Path) -> Vec<String> {
        let mut args: Vec<String> = vec![
            "--scene".into(),
            self.scene_arg.clone(),
            "--width".into(),
            self.size.to_string(),
            "--height".into(),
            self.size.to_string(),
            "--spes".into(),
            self.spes.to_string(),
            "--clock".into(),
            self.clock_ghz().to_string(),
            "--bvh-cache".into(),
            self.cache.to_string(),
            "--tri-cache".into(),
            self.cache.to_string(),
        ];
        if let Some(a) = self.assoc {
            args.extend(["--assoc".into(), a.to_string()]);
        }
        if let Some(n) = self.sht {
            args.extend(["--sht".into(), n.to_string()]);
        }
        if let Some(m) = self.shade {
            args.extend(["--shade".into(), m.to_string()]);
        }
        if self.draws_heatmap() {
            args.extend([
                "--heatmap".into(),
                self.heatmap_path(dir).display().to_string(),
            ]);
        }
        args.extend([
            "--stats".into(),
            self.stats_path(dir).display().to_string(),
            "-o".into(),
            self.image_path(dir).display().to_string(),
        ]);
        args
    }

    /// Whether this run also draws the scene's heat maps: the paper's base configuration
    /// (one 2.4 GHz SPE, 256-line direct-mapped caches, blocking DMA, no shading).
    pub fn draws_heatmap(&self) -> bool {
        self.spes == 1
            && self.clock_mhz == 2400
            && self.cache == 256
            && self.assoc.unwrap_or(1) == 1
            && self.sht.unwrap_or(1) == 1
            && self.shade.unwrap_or("none") == "none"
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
