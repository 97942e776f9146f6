//! `spu paper`: re-runs every experiment of the paper on the simulator and puts the paper's
//! numbers and ours side by side (report.md, report.html, report.json, the figures).
//!
//! The runs are independent frames, one [`spu_loader::render::RenderConfig`] each: rendered
//! here on host threads (sharing prepared scenes and compiled blocks, [`Kept`], and
//! admitted against a memory budget, [`Budget`]), or listed as `spu render` commands
//! (`--list-jobs`) to spread over machines and collected afterwards (`--collect`).

use crate::exit::{self, Error};
use crate::job_budget::{frame_estimate, Budget};
use crate::paper_jobs::{select_scenes, shell_word, Job};
use crate::paper_report::{build, Figure, HeatMaps, Report, ReportScene};
use crate::paper_tables::{tables, Measured, Setup, TableSpec};
use crate::prepared::{Kept, Sizes};
use spu_loader::stats::FrameStats;
use std::collections::{BTreeMap, BTreeSet};
use std::path::{Path, PathBuf};
use std::process::ExitCode;
use std::sync::atomic::{AtomicUsize, Ordering};
use std::sync::Mutex;

#[derive(clap::Args)]
pub struct Args {
    #[command(flatten)]
    ext: crate::options::ExtOption,
    /// Directory for the report, the figures and the jobs' files (jobs/).
    #[arg(long, default_value = "paper-report")]
    out: PathBuf,
    /// Every run at 256x256 instead of the paper's 1024x1024 (a first look, CI).
    #[arg(long)]
    quick: bool,
    /// Jobs run at once (each job simulates its SPEs on one host thread; a scene's BVH is
    /// built on this many).
    #[arg(long)]
    threads: Option<usize>,
    /// MiB the jobs in flight and the scenes kept prepared may take, by estimate: a thread
    /// waits before a job that does not fit (one larger than the whole budget runs alone).
    #[arg(long, value_name = "MIB", default_value_t = crate::job_budget::DEFAULT_MIB)]
    memory_budget: u64,
    /// Comma-separated scenes: room, conference, beetle (built in), shared-cornell-suzanne,
    /// shared-conference, shared-dragon (from --shared-scenes). Default: all present.
    #[arg(long)]
    scenes: Option<String>,
    /// Where the shared scene files are.
    #[arg(long, default_value = "../shared/scenes")]
    shared_scenes: PathBuf,
    /// Print each run's frame as the `spu render ... --stats FILE` command that renders it
    /// (files under OUT/jobs), and stop.
    #[arg(long)]
    list_jobs: bool,
    /// Build the report from the stats files in this directory instead of running.
    #[arg(long, conflicts_with = "list_jobs")]
    collect: Option<PathBuf>,
    /// Frame size (overrides --quick; small sizes keep tests short).
    #[arg(long, hide = true)]
    size: Option<u32>,
    /// Largest SPE count run (64; smaller keeps tests short).
    #[arg(long, hide = true, default_value_t = 64)]
    max_spes: usize,
}

pub fn run(args: Args) -> exit::Result<ExitCode> {
    let size = args.size.unwrap_or(if args.quick { 256 } else { 1024 });
    if !(8..=8192).contains(&size) {
        return Err(Error::input(format!("--size {size}: must be 8 to 8192")));
    }
    let most = spu_loader::render::MAX_SPES;
    if !(1..=most).contains(&args.max_spes) {
        return Err(Error::input(format!(
            "--max-spes {}: must be 1 to {most}",
            args.max_spes
        )));
    }
    if let Some(threads) = args.threads {
        // checked before --list-jobs too; what more threads than runs or cores means is
        // said below, where the runs are known
        crate::options::threads(Some(threads), threads, ("run", "runs"), threads)?;
    }
    let budget = crate::job_budget::parse_mib(args.memory_budget).map_err(Error::input)?;
    let (scenes, notes) = select_scenes(args.scenes.as_deref(), &args.shared_scenes)?;
    let setup = Setup {
        scenes,
        size,
        max_spes: args.max_spes,
    };
    let specs = tables(&setup);
    let jobs = unique_jobs(&specs);
    let jobs_dir = args.out.join("jobs");

    if args.list_jobs {
        // the listed renders write their files there, and a renderer does not make folders;
        // a folder that cannot be made is bad input, found before any work (status 2)
        std::fs::create_dir_all(&jobs_dir)
            .map_err(|e| Error::input(format!("--out: {}: {e}", jobs_dir.display())))?;
        let exe = std::env::current_exe()
            .ok()
            .and_then(|p| p.to_str().map(str::to_string))
            .unwrap_or_else(|| "spu".into());
        for job in &jobs {
            let words: Vec<String> = std::iter::once(exe.clone())
                .chain(std::iter::once("render".to_string()))
                .chain(crate::render_options::words(
                    &with_ext(job, args.ext.ext),
                    &job.outputs(&jobs_dir),
                ))
                .chain(match job.frames {
                    0 => Vec::new(),
                    n => vec!["--frames".to_string(), n.to_string()],
                })
                .map(|w| shell_word(&w))
                .collect();
            outln!("{}", words.join(" "));
        }
        return Ok(ExitCode::SUCCESS);
    }

    let (threads, thread_notes) = if args.collect.is_some() {
        (1, Vec::new())
    } else {
        crate::options::threads(
            args.threads,
            jobs.len(),
            ("run", "runs"),
            crate::options::host_cores(),
        )?
    };
    prepare_out(&args.out)?;
    // the most the budget saw in flight and kept at once, for the closing note
    let mut estimated = None;
    let stats_dir = match &args.collect {
        Some(dir) => {
            if !dir.is_dir() {
                return Err(Error::input(format!(
                    "--collect {}: not a directory",
                    dir.display()
                )));
            }
            check_collected(&jobs, dir, &args.out)?;
            dir.clone()
        }
        None => {
            for note in thread_notes {
                eprintln!("spu: {note}");
            }
            std::fs::create_dir_all(&jobs_dir).map_err(|e| Error::output(&jobs_dir, e))?;
            let budget = Budget::new(budget);
            run_jobs(&jobs, &jobs_dir, threads, &budget, args.ext.ext);
            if budget.ran_alone() > 0 {
                eprintln!(
                    "spu paper: {} runs were estimated larger than --memory-budget {} MiB and ran alone",
                    budget.ran_alone(),
                    args.memory_budget
                );
            }
            estimated = Some(budget.most());
            jobs_dir
        }
    };
    let results = collect(&jobs, &stats_dir);
    let missing: Vec<String> = results
        .values()
        .filter_map(|r| r.as_ref().err().cloned())
        .collect();
    let tables = build(&specs, &results);
    let mut report = Report {
        size,
        scenes: setup
            .scenes
            .iter()
            .map(|s| ReportScene {
                id: s.id.clone(),
                source: s.render_name.clone(),
                paper: s.paper.name().into(),
            })
            .collect(),
        jobs: jobs.len(),
        jobs_measured: results.values().filter(|r| r.is_ok()).count(),
        tables,
        figures: Vec::new(),
        missing: missing.clone(),
        heatmaps: heatmaps(&jobs, &stats_dir, &args.out),
        notes,
        verdicts: Vec::new(),
    };
    let scene_ids: Vec<String> = setup.scenes.iter().map(|s| s.id.clone()).collect();
    report.verdicts = crate::paper_beyond::verdicts(&report.tables, &scene_ids);
    report
        .verdicts
        .extend(crate::paper_next::verdicts(&report.tables, &scene_ids));
    if let Some(t) = report.tables.iter().find(|t| t.id == "figure2") {
        let series = crate::paper_figure::series(t);
        let files = crate::paper_figure::write_figure2(&args.out, "figure2", &series)
            .map_err(Error::failure)?;
        report.figures.push(Figure {
            id: "figure2".into(),
            title: "Figure 2: speed-up over SPEs".into(),
            files,
        });
    }
    beyond_figures(&mut report, &args.out)?;
    write(&args.out.join("report.json"), &{
        let mut s =
            serde_json::to_string_pretty(&report).map_err(|e| Error::failure(e.to_string()))?;
        s.push('\n');
        s
    })?;
    write(&args.out.join("report.md"), &report.to_markdown())?;
    write(&args.out.join("report.html"), &report.to_html())?;
    write(&args.out.join("results.md"), &report.to_results_markdown())?;
    eprintln!(
        "wrote {}/report.md, report.html, report.json, results.md and the figures ({} of {} runs measured)",
        args.out.display(),
        report.jobs_measured,
        report.jobs
    );
    if let Some(bytes) = crate::peak_memory::peak_resident_bytes() {
        let runs = match args.collect {
            Some(_) => "collected, none run".to_string(),
            None => match threads.min(jobs.len()).max(1) {
                1 => "one run at a time".to_string(),
                n => format!("up to {n} runs at once"),
            },
        };
        let estimated = estimated.map_or(String::new(), |b: u64| {
            format!(
                "; at most {} MiB estimated in flight, budget {} MiB",
                b.div_ceil(1 << 20),
                args.memory_budget
            )
        });
        eprintln!(
            "peak memory: {} MiB resident on this host ({runs}{estimated})",
            bytes.div_ceil(1 << 20)
        );
    }
    if missing.is_empty() {
        Ok(ExitCode::SUCCESS)
    } else {
        // stats that a --collect directory lacks are bad input; runs that failed here are
        // failures
        let status = if args.collect.is_some() {
            exit::Status::BadInput
        } else {
            exit::Status::Failure
        };
        Err(Error::new(
            status,
            format!(
                "{} of {} runs have no statistics (the report says which):\n  {}",
                missing.len(),
                jobs.len(),
                missing.join("\n  ")
            ),
        ))
    }
}

/// The figures of "Beyond the paper", from its tables: rays per second against hint
/// entries, against clock, and frame rate against SPE count.
fn beyond_figures(report: &mut Report, out: &Path) -> exit::Result<()> {
    use crate::paper_beyond::{self as beyond, Axes, Curve};
    let find = |id: &str| report.tables.iter().find(|t| t.id == id);
    let mut figures = Vec::new();
    if let Some(t) = find(beyond::TABLES[0]) {
        // primary rays: "none" is the real SPU's one hint entry
        let curves: Vec<Curve> = report
            .scenes
            .iter()
            .filter_map(|sc| {
                let points: Vec<(f64, f64)> = beyond::extension_settings()
                    .iter()
                    .filter_map(|ext| {
                        let n = match *ext {
                            "none" => 1.0,
                            other => other.strip_prefix("multihint=")?.parse().ok()?,
                        };
                        let label = format!("none, ext {ext}: MRays/s");
                        let row = t
                            .rows
                            .iter()
                            .find(|r| r.scene == sc.id && r.label == label)?;
                        Some((n, row.ours?))
                    })
                    .collect();
                (!points.is_empty()).then(|| Curve {
                    label: sc.id.clone(),
                    points,
                })
            })
            .collect();
        figures.push((
            beyond::TABLES[0],
            "beyond-hints",
            Axes {
                caption: "Primary rays against branch hint entries",
                x: "hint entries (1: the real SPU)",
                y: "MRays/s on one 2.4 GHz SPE",
            },
            curves,
        ));
    }
    if let Some(t) = find(beyond::TABLES[1]) {
        let curves = beyond::curves(t, &["SHT 1, ", "SHT 4, "], " GHz", &beyond::CLOCKS);
        figures.push((
            beyond::TABLES[1],
            "beyond-clock",
            Axes {
                caption: "MRays/s per SPE against clock, 100 ns memory",
                x: "clock (GHz)",
                y: "MRays/s per SPE",
            },
            curves,
        ));
    }
    if let Some(t) = find(beyond::TABLES[2]) {
        let xs: Vec<f64> = beyond::SPE_COUNTS.iter().map(|&n| n as f64).collect();
        let curves = beyond::curves(t, &[""], " SPEs: fps", &xs);
        figures.push((
            beyond::TABLES[2],
            "beyond-spes",
            Axes {
                caption: "Frame rate against SPEs, one 25.6 GB/s memory",
                x: "SPEs",
                y: "fps at 1024x1024, simple shading",
            },
            curves,
        ));
    }
    for (id, stem, axes, curves) in figures {
        if curves.is_empty() {
            continue;
        }
        let files = beyond::write_figure(out, stem, &axes, &curves).map_err(Error::failure)?;
        report.figures.push(Figure {
            id: id.into(),
            title: axes.caption.into(),
            files,
        });
    }
    Ok(())
}

/// The heat maps the jobs drew, where they exist, as paths relative to the report.
fn heatmaps(jobs: &[Job], dir: &Path, out: &Path) -> Vec<HeatMaps> {
    let relative = |p: &Path| p.strip_prefix(out).unwrap_or(p).display().to_string();
    jobs.iter()
        .filter(|j| j.draws_heatmap())
        .filter_map(|j| {
            let (cycles, wait) = crate::heatmap::paths(&j.heatmap_path(dir));
            (cycles.is_file() && wait.is_file()).then(|| HeatMaps {
                scene: j.scene_id.clone(),
                config: j.describe(),
                cycles: relative(&cycles),
                wait: relative(&wait),
            })
        })
        .collect()
}

/// Every job of every row, once, in a stable order.
pub fn unique_jobs(specs: &[TableSpec]) -> Vec<Job> {
    let set: BTreeSet<Job> = specs
        .iter()
        .flat_map(|t| &t.rows)
        .filter_map(|r| r.jobs.as_ref().ok())
        .flatten()
        .cloned()
        .collect();
    set.into_iter().collect()
}

/// Makes the output directory and checks that files can be written into it, before any
/// work starts.
fn prepare_out(out: &Path) -> exit::Result<()> {
    std::fs::create_dir_all(out)
        .map_err(|e| Error::input(format!("--out {}: {e}", out.display())))?;
    exit::check_writable(&out.join("report.json"))
        .map_err(|e| Error::input(format!("--out: {}", e.message.unwrap_or_default())))
}

/// The files the report is written to (the figures besides).
const REPORT_FILES: [&str; 12] = [
    "report.json",
    "report.md",
    "report.html",
    "results.md",
    "figure2.png",
    "figure2.svg",
    "beyond-hints.png",
    "beyond-hints.svg",
    "beyond-clock.png",
    "beyond-clock.svg",
    "beyond-spes.png",
    "beyond-spes.svg",
];

/// No report file overwrites a stats file or heat map `--collect` reads.
fn check_collected(jobs: &[Job], dir: &Path, out: &Path) -> exit::Result<()> {
    let mut files = crate::outputs::Files::new();
    for job in jobs {
        let (cycles, wait) = crate::heatmap::paths(&job.heatmap_path(dir));
        for path in [job.stats_path(dir), cycles, wait] {
            files.input("the collected", &path);
        }
    }
    for name in REPORT_FILES {
        files.output("--out", &out.join(name));
    }
    files.check()
}

fn write(path: &Path, text: &str) -> exit::Result<()> {
    exit::write_file(path, text.as_bytes())
}

/// Runs the jobs on `threads` host threads, one bar over all of them, each job admitted
/// against `budget`; a job that fails leaves no stats file and the report names it.
fn run_jobs(jobs: &[Job], dir: &Path, threads: usize, budget: &Budget, ext: spu_isa::Extensions) {
    // the heaviest scenes first, so that no long job starts last
    let mut order: Vec<&Job> = jobs.iter().collect();
    order.sort_by_key(|j| std::cmp::Reverse(weight(j)));
    let bar = indicatif::ProgressBar::new(jobs.len() as u64);
    bar.set_style(
        indicatif::ProgressStyle::with_template(
            "{spinner} runs {pos}/{len} {bar:30} {elapsed_precise} (eta {eta}) {wide_msg}",
        )
        .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
    );
    let next = AtomicUsize::new(0);
    // Each scene is prepared once (its BVH on all the threads) and kept while runs of it
    // remain.
    let kept = Kept::new(threads);
    let mut left: BTreeMap<&str, usize> = BTreeMap::new();
    for job in jobs {
        *left.entry(job.scene_arg.as_str()).or_default() += 1;
    }
    let left = Mutex::new(left);
    let running: Mutex<BTreeSet<String>> = Mutex::new(BTreeSet::new());
    let failures: Mutex<Vec<String>> = Mutex::new(Vec::new());
    let show = |running: &BTreeSet<String>| {
        bar.set_message(running.iter().cloned().collect::<Vec<_>>().join(", "));
    };
    std::thread::scope(|scope| {
        for _ in 0..threads.min(jobs.len()).max(1) {
            scope.spawn(|| loop {
                // the ticket of the job: jobs are admitted in this order, every ticket
                // once (a failed preparation too), so none waits for a ticket never shown
                let ticket = next.fetch_add(1, Ordering::Relaxed);
                let Some(job) = order.get(ticket) else { break };
                let name = job.name();
                let prepared = estimate(job, &kept, budget);
                let bytes = prepared.as_ref().map_or(0, |(bytes, _)| *bytes);
                let admission = budget.admit(ticket, bytes);
                if let Ok(mut r) = running.lock() {
                    r.insert(name.clone());
                    show(&r);
                }
                let outcome = prepared.and_then(|(_, scene)| {
                    run_job(job, scene.as_deref(), dir, &kept, threads, ext)
                });
                drop(admission);
                if let Err(e) = outcome {
                    if let Ok(mut f) = failures.lock() {
                        f.push(format!("{name}: {e}"));
                    }
                }
                if let Ok(mut left) = left.lock() {
                    let n = left.entry(job.scene_arg.as_str()).or_default();
                    *n = n.saturating_sub(1);
                    if *n == 0 {
                        if let Some(sizes) = kept.forget(&job.scene_arg) {
                            budget.release(sizes.prepared);
                        }
                    }
                }
                if let Ok(mut r) = running.lock() {
                    r.remove(&name);
                    show(&r);
                }
                bar.inc(1);
            });
        }
    });
    bar.finish_and_clear();
    for f in failures.into_inner().unwrap_or_default() {
        eprintln!("spu paper: run failed: {f}");
    }
}

/// The bytes `job` is estimated to take (docs/parallel.md, "Peak memory"), with its scene
/// prepared (kept, and counted in `budget` while kept) where it is a still frame.
fn estimate(
    job: &Job,
    kept: &Kept,
    budget: &Budget,
) -> Result<(u64, Option<std::sync::Arc<spu_loader::render::Prepared>>), String> {
    let pixels = job.size as u64 * job.size as u64;
    let keep = |sizes: Sizes| budget.keep(sizes.prepared);
    if job.frames == 0 {
        let scene = kept.prepare(&job.scene_arg, keep)?;
        let sizes = Sizes::of(&scene);
        return Ok((
            frame_estimate(sizes.image, pixels, job.spes as u64),
            Some(scene),
        ));
    }
    // A moving scene prepares its own frames: its animation and tree, and each frame
    // staged, beside a frame's main memory, each about its still scene's size. The still
    // scene is prepared if it has not been yet (its own frames follow and forget it).
    let still = crate::paper_next::still_scene(&job.scene_arg).and_then(|still| {
        kept.sizes(still)
            .or_else(|| kept.prepare(still, keep).ok().map(|p| Sizes::of(&p)))
    });
    Ok(match still {
        Some(sizes) => (
            (2 * sizes.prepared).saturating_add(frame_estimate(
                sizes.image,
                pixels,
                job.spes as u64,
            )),
            None,
        ),
        // not a scene known to move: the whole budget, so it runs alone
        None => (budget.limit(), None),
    })
}

/// The frame `job` renders, on SPUs with the ISA extensions `ext` (`--ext`: every run of
/// the report with them; docs/extensions.md).
fn with_ext(job: &Job, ext: spu_isa::Extensions) -> spu_loader::render::RenderConfig {
    use spu_loader::render::RenderConfig;
    let config = job.config();
    if job.ext != "none" {
        // the run of a "Beyond the paper" row: its own extensions
        return config;
    }
    RenderConfig {
        kernel: RenderConfig::kernel_with(!config.kernel.traces(), config.shading.mode, ext),
        extensions: ext,
        ..config
    }
}

/// A rough cost for ordering: rays times the scene's heaviness.
fn weight(job: &Job) -> u64 {
    let scene = match job.scene_id.as_str() {
        "room" | "shared-cornell-suzanne" => 1,
        _ => 10,
    };
    scene * job.size as u64 * job.size as u64
}

/// One job in this process, as `spu render` renders and writes a frame of `prepared`
/// (none for a moving scene, which prepares its frames itself, its trees built on
/// `bvh_threads`); its stats file is removed first so that a failed run leaves none.
fn run_job(
    job: &Job,
    prepared: Option<&spu_loader::render::Prepared>,
    dir: &Path,
    kept: &Kept,
    bvh_threads: usize,
    ext: spu_isa::Extensions,
) -> Result<(), String> {
    let stats = job.stats_path(dir);
    let _ = std::fs::remove_file(&stats);
    let Some(prepared) = prepared else {
        return crate::paper_next::run_frames(
            &with_ext(job, ext),
            job.frames,
            &job.outputs(dir),
            &kept.code,
            bvh_threads,
        );
    };
    crate::cmd_render::frame(prepared, &with_ext(job, ext), &job.outputs(dir), &kept.code)
        .map_err(|e| e.message.unwrap_or_default())?;
    Ok(())
}

/// Reads every job's stats file from `dir`: the statistics, or why there are none.
pub fn collect(jobs: &[Job], dir: &Path) -> BTreeMap<String, Result<Measured, String>> {
    jobs.iter()
        .map(|job| {
            let path = job.stats_path(dir);
            let result = match std::fs::read_to_string(&path) {
                Err(e) => Err(format!("{}: {e}", path.display())),
                Ok(text) => read_stats(&text, job).map_err(|e| format!("{}: {e}", path.display())),
            };
            (job.name(), result)
        })
        .collect()
}

fn read_stats(text: &str, job: &Job) -> Result<Measured, String> {
    if job.frames > 0 {
        let frames: Vec<spu_loader::animate::FrameStats> =
            serde_json::from_str(text).map_err(|e| e.to_string())?;
        if frames.len() != job.frames as usize {
            return Err(format!(
                "holds {} frames, not the job's {}",
                frames.len(),
                job.frames
            ));
        }
        // a frame the host rebuilt has no refit to count SPEs by
        if let Some(f) = frames
            .iter()
            .find(|f| !f.rebuilt && f.refit_spes.len() != job.spes)
        {
            return Err(format!(
                "frame {} was refitted on {} SPEs, not the job's {}",
                f.frame,
                f.refit_spes.len(),
                job.spes
            ));
        }
        return Ok(Measured::Frames(frames));
    }
    let stats = FrameStats::from_json(text)?;
    let raw: serde_json::Value = serde_json::from_str(text).map_err(|e| e.to_string())?;
    if stats.width != job.size || stats.height != job.size || stats.spus.len() != job.spes {
        return Err(format!(
            "holds a {}x{} frame on {} SPEs, not the job's {}x{} on {}",
            stats.width,
            stats.height,
            stats.spus.len(),
            job.size,
            job.size,
            job.spes
        ));
    }
    let c = &stats.config;
    // files written before the configuration was recorded have none (sht 0)
    if c.sht != 0
        && (c.sht != job.sht
            || c.assoc != job.assoc
            || c.bvh_cache_lines != job.cache
            || c.tri_cache_lines != job.cache)
    {
        return Err(format!(
            "holds a run with SHT {}, {}-way {}/{}-line caches, not the job's",
            c.sht, c.assoc, c.bvh_cache_lines, c.tri_cache_lines
        ));
    }
    Ok(Measured::Frame(Box::new(crate::paper_tables::Frame {
        stats,
        raw,
    })))
}
