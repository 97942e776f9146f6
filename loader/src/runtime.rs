//! The multi-SPE runtime: starts N simulated SPUs on a shared main memory, lets them take
//! tiles from the shared counter, and collects the frame buffer and the statistics.

use crate::frame::FrameLayout;
use crate::kernel_abi::{KernelStats, STATS_BYTES};
use crate::layout::StagedScene;

/// What one SPU did in a frame.
#[derive(Clone, Debug, Default)]
pub struct SpuReport {
    pub cycles: u64,
    pub instructions: u64,
    /// Of `instructions`, those run by compiled blocks (0 with the interpreter).
    pub compiled_instructions: u64,
    pub tiles: u64,
    pub stats: KernelStats,
}

pub use crate::kernel_abi::{ShadeCounters, SHADE_STATS_OFFSET};

/// The outcome of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameRun {
    pub frame_buffer: Vec<u8>,
    /// The 32-bit colour frame buffer of a shaded frame.
    pub colour_buffer: Option<Vec<u8>>,
    /// Per SPU, the shading module's counters (intersection packets with a hit, of them
    /// on one triangle, passes, packets, vertex lookups, misses, material lookups, misses,
    /// triangle records looked up in the traversal's triangle cache, fetched past it).
    pub shade_counters: Vec<ShadeCounters>,
    /// Shadow rays the shadow module cast (`--shade shadows`), summed over the SPUs.
    pub shadow_rays: u64,
    /// A reflect frame's: per bounce (the first reflection first), the reflection
    /// module's counters summed over the SPUs, and the bounce-hit buffer (per packet, per
    /// bounce: 64 triangle records or -1, 64 distances).
    pub reflect_counters: Vec<crate::kernel_abi::ReflectCounters>,
    pub bounce_hits: Option<Vec<u8>>,
    pub frame_cycles: u64,
    pub spus: Vec<SpuReport>,
    /// The timing model's counters, merged over all SPUs.
    pub profile: Option<spu_isa::profile::Profile>,
    /// Bytes the SPUs' MFCs read from and wrote to each named main-memory region, summed
    /// over the SPUs: `(region, read, written)` (see [`traffic_regions`]).
    pub traffic: Vec<(String, u64, u64)>,
    /// The kernel's symbols (to split the profile by code section).
    pub symbols: Vec<(String, u32)>,
    /// The kernel's local-store image (to tell its no-ops apart in the profile).
    pub kernel_image: Vec<u8>,
    /// Each SPU's MFC commands and channel waits, when [`Frame::event_log`] was on.
    pub events: Vec<Vec<spu_isa::machine::SpuEvent>>,
    /// The caches, packets in flight and memory latency the frame ran with.
    pub config: KernelConfig,
    /// The block compiler's work for the frame (its SPUs share one code cache), with
    /// the instructions run compiled summed over the SPUs.
    pub jit: spu_isa::jit::JitStats,
}

/// The kernel configuration of a frame, as `--stats` reports it.
#[derive(Clone, Debug, Default, PartialEq, serde::Serialize, serde::Deserialize)]
pub struct KernelConfig {
    /// Packets each SPU keeps in flight (software hyperthreading; 1 = blocking misses).
    pub sht: u32,
    /// Ways of both caches (1 = direct mapped, 4 = 4-way LRU).
    pub assoc: u32,
    pub bvh_cache_lines: u32,
    pub tri_cache_lines: u32,
    pub dma_latency_ns: f64,
}

impl KernelConfig {
    pub fn new(layout: &FrameLayout, dma_latency_ns: f64) -> Self {
        let p = &layout.params;
        KernelConfig {
            sht: p.sht_contexts,
            assoc: p.cache_assoc,
            bvh_cache_lines: 1 << p.bvh_cache_log2,
            tri_cache_lines: 1 << p.tri_cache_log2,
            dma_latency_ns,
        }
    }
}

impl FrameRun {
    /// The kernel statistics summed over all SPUs.
    pub fn kernel_stats(&self) -> KernelStats {
        let mut total = KernelStats::default();
        for s in &self.spus {
            total.merge(&s.stats);
        }
        total
    }
}

/// An assembled SPU program: a flat local-store image and its entry point.
#[derive(Clone, Debug)]
pub struct Program {
    pub image: Vec<u8>,
    pub entry: u32,
    pub symbols: Vec<(String, u32)>,
}

/// Assembles a kernel with its includes from memory (`layout.inc`, the kernel modules).
pub fn assemble_kernel(source: &str, name: &str) -> Result<Program, String> {
    assemble_kernel_with(source, name, &[])
}

/// Assembles a kernel with its includes from memory and `defines` (as `--defsym`: `SHADE`
/// selects the shading kernel).
pub fn assemble_kernel_with(
    source: &str,
    name: &str,
    defines: &[(&str, i64)],
) -> Result<Program, String> {
    let includes = crate::kernels::include_files();
    if let Some((image, entry, symbols)) =
        crate::kernels::prebuilt(source, name, defines, &includes)
    {
        return Ok(Program {
            image,
            entry,
            symbols,
        });
    }
    let opts = spu_asm::Options {
        virtual_files: includes,
        defines: defines.iter().map(|(n, v)| (n.to_string(), *v)).collect(),
        ..Default::default()
    };
    match spu_asm::assemble(source, name, &opts) {
        Ok(out) => Ok(Program {
            image: out.image,
            entry: out.entry,
            symbols: out.symbols,
        }),
        Err(diagnostics) => Err(diagnostics
            .iter()
            .map(|d| d.to_string())
            .collect::<Vec<_>>()
            .join("\n")),
    }
}

/// The main-memory regions whose traffic a frame counts, by name: the scene's node,
/// triangle-record, vertex and material arrays (the paper's Table 6 rows), the packet
/// result blocks and, for a shaded frame, the 32-bit colour frame buffer.
pub fn traffic_regions(staged: &StagedScene, layout: &FrameLayout) -> Vec<(String, u64, u64)> {
    use crate::layout::{MATERIAL_SIZE, NODE_SIZE, TRI_SIZE, VERTEX_SIZE};
    let h = &staged.header;
    let array = |addr: u32, count: u32, size: usize| {
        (addr as u64, addr as u64 + count as u64 * size as u64)
    };
    let mut regions = vec![
        ("bvh_nodes", array(h.node_addr, h.node_count, NODE_SIZE)),
        (
            "triangle_records",
            array(h.triangle_addr, h.triangle_count, TRI_SIZE),
        ),
        (
            "vertices",
            array(h.vertex_addr, h.vertex_count, VERTEX_SIZE),
        ),
        (
            "materials",
            array(h.material_addr, h.material_count, MATERIAL_SIZE),
        ),
        (
            "result_blocks",
            (
                layout.frame_buffer_addr as u64,
                layout.frame_buffer_addr as u64 + layout.frame_buffer_len as u64,
            ),
        ),
    ];
    if let Some(shading) = &layout.shading {
        regions.push((
            "colour_frame_buffer",
            (
                shading.colour_addr as u64,
                shading.colour_addr as u64 + shading.colour_len as u64,
            ),
        ));
    }
    regions
        .into_iter()
        .map(|(name, (start, end))| (name.to_string(), start, end))
        .collect()
}

/// Local store of one SPU.
pub const LOCAL_STORE_BYTES: u32 = 256 * 1024;

/// The caches and packet contexts the kernel carves after its `cache_area` must fit in the
/// local store.
fn check_local_store(program: &Program, layout: &FrameLayout) -> Result<(), String> {
    let Some(start) = program
        .symbols
        .iter()
        .find(|(n, _)| n == "cache_area")
        .map(|(_, a)| *a)
    else {
        return Ok(());
    };
    let p = &layout.params;
    let (bvh, tri, sht) = (
        1u32 << p.bvh_cache_log2,
        1u32 << p.tri_cache_log2,
        p.sht_contexts.max(1),
    );
    let end = start as u64 + crate::kernel_abi::carved_bytes(bvh, tri, sht) as u64;
    if end > LOCAL_STORE_BYTES as u64 {
        return Err(format!(
            "local store: {bvh} BVH and {tri} triangle cache lines and {sht} packet contexts need {} bytes after the kernel's {start} bytes, {} available",
            end - start as u64,
            LOCAL_STORE_BYTES - start.min(LOCAL_STORE_BYTES)
        ));
    }
    Ok(())
}

/// A leaf's triangles are fetched into a packet context's staging slots, so no leaf may hold
/// more of them than there are slots.
fn check_leaves_fit(staged: &StagedScene) -> Result<(), String> {
    let limit = crate::kernel_abi::context::STAGE_TRIANGLES;
    match staged.nodes.iter().map(|n| n.triangle_count()).max() {
        Some(most) if most > limit => Err(format!(
            "a BVH leaf holds {most} triangles; the kernel fetches at most {limit} per leaf"
        )),
        _ => Ok(()),
    }
}

/// Simulated cycles each SPU runs between two synchronisations of main memory. Writes and
/// atomic updates become visible to other SPUs at these boundaries, in a fixed order, so a
/// frame's result does not depend on how the SPUs are spread over host threads.
pub const QUANTUM_CYCLES: u64 = 10_000;

/// The quantum of a frame on `spes` SPEs: [`QUANTUM_CYCLES`] up to a dual Cell's 16. A
/// contended atomic (the tile counter every SPE claims its tiles from) lets one SPE through
/// per quantum, so beyond 16 the quantum shrinks with the SPE count: the first round of
/// claims then costs at most the 160,000 cycles it costs 16 SPEs (`docs/memory-model.md`).
pub fn quantum_cycles(spes: usize) -> u64 {
    const DUAL_CELL: u64 = 16;
    QUANTUM_CYCLES * DUAL_CELL / (spes as u64).max(DUAL_CELL)
}

/// Stop code of a kernel that finished its frame (`stop 0x2000`, exit status 0).
pub const STOP_DONE: u16 = 0x2000;

/// Why a frame did not complete, in kinds a caller can tell apart (`spu render` gives each
/// its own exit status).
#[derive(Debug, Clone, PartialEq)]
pub enum FrameError {
    /// The frame could not be set up (the kernel did not assemble, ...).
    Setup(String),
    /// The SPUs had not all finished within `limit` cycles each (`--max-cycles`, per SPE):
    /// each SPE's clock when the frame stopped (never past `limit`), and the SPEs the
    /// limit stopped (the others had finished).
    CycleLimit {
        limit: u64,
        cycles: Vec<u64>,
        stopped: Vec<usize>,
    },
    /// An SPU stopped abnormally (illegal instruction, DMA error, deadlock, ...).
    SpuStopped { spu: usize, reason: String },
}

impl std::fmt::Display for FrameError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FrameError::Setup(message) => f.write_str(message),
            FrameError::CycleLimit {
                limit,
                cycles,
                stopped,
            } => {
                let list = |spes: &[usize]| {
                    spes.iter()
                        .map(usize::to_string)
                        .collect::<Vec<_>>()
                        .join(", ")
                };
                // Those the limit stopped are at it, unless one waited on the host.
                let (at_limit, before): (Vec<usize>, Vec<usize>) =
                    stopped.iter().partition(|&&i| cycles[i] == *limit);
                let mut parts = Vec::new();
                if !at_limit.is_empty() {
                    parts.push(format!("SPE {} stopped at cycle {limit}", list(&at_limit)));
                }
                for i in before {
                    parts.push(format!("SPE {i} stopped at cycle {}", cycles[i]));
                }
                for i in (0..cycles.len()).filter(|i| !stopped.contains(i)) {
                    parts.push(format!("SPE {i} had finished at cycle {}", cycles[i]));
                }
                write!(
                    f,
                    "the frame did not finish within {limit} cycles per SPE: {}",
                    parts.join("; ")
                )
            }
            FrameError::SpuStopped { spu, reason } => write!(f, "SPU {spu} stopped: {reason}"),
        }
    }
}

impl From<String> for FrameError {
    fn from(message: String) -> FrameError {
        FrameError::Setup(message)
    }
}

impl From<FrameError> for String {
    fn from(error: FrameError) -> String {
        error.to_string()
    }
}

/// One frame ready to run: the staged scene, the frame's layout (whole: see
/// [`crate::render::frame_layout`]) and the program, and how to run them.
pub struct Frame<'a> {
    pub staged: &'a StagedScene,
    pub layout: &'a FrameLayout,
    /// The assembled `kernel`, as it is loaded into every SPU.
    pub program: &'a Program,
    pub kernel: crate::kernels::KernelVariant,
    pub spes: usize,
    /// Host threads running the SPUs (the result does not depend on it).
    pub threads: usize,
    /// The timing model's settings; with `timed` off they give only the DMA latency the
    /// statistics report.
    pub timing: spu_isa::timing::TimingConfig,
    /// Whether the SPUs run with the timing model.
    pub timed: bool,
    pub engine: spu_isa::jit::Engine,
    /// Simulated cycles per SPU before the frame gives up.
    pub max_cycles: u64,
    /// Log every SPU's MFC commands and channel waits (for heat maps and timelines).
    pub event_log: bool,
    /// The compiled blocks the SPEs share, and add to: earlier frames' blocks are reused.
    /// The frame's results do not depend on it, only how much runs compiled and how soon.
    pub code: &'a spu_isa::jit::CodeCache,
    /// The ISA extensions the SPUs run with (their hint entries override `timing`'s).
    pub extensions: spu_isa::Extensions,
}

/// Runs `frame` with its SPUs on its host threads; `progress` hears the number of tiles
/// taken so far and the frame's tiles. The library's callers go through
/// [`crate::render::render`], which makes the layout and chooses the program.
pub fn run_frame(
    frame: &Frame,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<FrameRun, FrameError> {
    use spu_isa::machine::{MainMemory, StopReason};
    use spu_spe::{ContextConfig, Outcome, Quantum, State, System};
    use std::ops::ControlFlow;
    let Frame {
        staged,
        layout,
        program,
        kernel,
        spes,
        threads,
        max_cycles,
        code,
        ..
    } = *frame;
    let (fill, shaded) = (!kernel.traces(), kernel.shades());
    if shaded != layout.shading.is_some() {
        return Err(FrameError::Setup(format!(
            "the {} kernel {} a shading block in the frame's layout",
            kernel.id(),
            if shaded { "needs" } else { "takes no" }
        )));
    }
    if !fill {
        check_local_store(program, layout)?;
        check_leaves_fit(staged)?;
    }
    let regions = traffic_regions(staged, layout);
    let mut system = System::with_memory(MainMemory::new(layout.memory_image(staged)));
    system.set_quantum(Quantum::Aligned(quantum_cycles(spes)));
    system.set_threads(threads);
    // The SPEs run the same kernel: each block is compiled once for all of them.
    let compiled_before = code.stats();
    for i in 0..spes {
        let id = system.create_context(ContextConfig {
            engine: frame.engine,
            timing: frame.timed.then(|| frame.timing.clone()),
            code: Some(code.clone()),
            extensions: frame.extensions,
        });
        let spu = system.spu_mut(id);
        spu.load_image(&program.image);
        spu.set_pc(program.entry);
        spu.set_reg(3, [i as u32, 0, 0, 0]);
        spu.set_reg(4, [layout.param_addr, 0, 0, 0]);
        spu.count_traffic(regions.iter().map(|(_, s, e)| (*s, *e)).collect());
        if frame.event_log {
            spu.enable_event_log();
        }
    }
    let done = |state: &State| *state == State::Stopped(StopReason::Stop(STOP_DONE));
    let outcome = system.run_observed(max_cycles, |memory, states| {
        let taken = memory
            .read_u32(layout.counter_addr)
            .min(layout.params.num_tiles);
        progress(taken, layout.params.num_tiles);
        // An SPU that stopped any other way ends the frame at once.
        let failed = states
            .iter()
            .any(|s| !done(s) && !matches!(s, State::Runnable | State::Waiting { .. }));
        if failed {
            ControlFlow::Break(())
        } else {
            ControlFlow::Continue(())
        }
    });
    let contexts: Vec<_> = system.contexts().collect();
    for (i, &id) in contexts.iter().enumerate() {
        let reason = match system.state(id).clone() {
            state if done(&state) => {
                if system.read_out_mbox(id) == Some(1) {
                    continue;
                }
                "without its end-of-frame message".to_string()
            }
            State::Runnable => continue,
            State::Waiting { channel, pc } => {
                format!("deadlock at {pc:#x} on channel {}", channel.number())
            }
            State::Stopped(other) => other.to_string(),
            State::Faulted { message, .. } => message,
        };
        if outcome != Outcome::CycleLimit {
            return Err(FrameError::SpuStopped { spu: i, reason });
        }
    }
    if outcome == Outcome::CycleLimit {
        return Err(FrameError::CycleLimit {
            limit: max_cycles,
            cycles: contexts.iter().map(|&id| system.spu(id).cycles()).collect(),
            stopped: (0..contexts.len())
                .filter(|&i| !done(system.state(contexts[i])))
                .collect(),
        });
    }
    let finished: Vec<Option<u64>> = contexts
        .iter()
        .map(|&id| Some(system.spu(id).cycles()))
        .collect();
    let events = contexts
        .iter()
        .map(|&id| system.spu_mut(id).take_events())
        .collect();
    let spus: Vec<&spu_isa::machine::Spu> = contexts.iter().map(|&id| system.spu(id)).collect();
    let memory = system.memory();
    let stats_base = layout.stats_addr as usize;
    let spus_report = spus
        .iter()
        .enumerate()
        .map(|(i, spu)| {
            let block =
                &memory.bytes()[stats_base + i * STATS_BYTES..stats_base + (i + 1) * STATS_BYTES];
            let stats = KernelStats::from_be_bytes(block);
            SpuReport {
                cycles: finished[i].unwrap_or(0),
                instructions: spu.instructions(),
                compiled_instructions: spu.jit_stats().compiled_instructions,
                tiles: if fill {
                    stats.traversal_steps
                } else {
                    stats.packets / 64
                },
                stats,
            }
        })
        .collect::<Vec<_>>();
    let fb = layout.frame_buffer_addr as usize;
    let mut profile: Option<spu_isa::profile::Profile> = None;
    for spu in &spus {
        if let Some(t) = spu.timing() {
            let p = t.finish_profile();
            match &mut profile {
                Some(total) => total.merge(&p),
                None => profile = Some(p),
            }
        }
    }
    let shadow_rays = match &layout.shading {
        Some(_) => {
            let at = layout.params.ls_shading as usize
                + crate::kernel_abi::SHADOW_AREA
                + crate::kernel_abi::SHADOW_RAYS_OFFSET;
            spus.iter()
                .map(|spu| {
                    let w = &spu.ls()[at..at + 4];
                    u32::from_be_bytes([w[0], w[1], w[2], w[3]]) as u64
                })
                .sum()
        }
        _ => 0,
    };
    let (colour_buffer, shade_counters) = match &layout.shading {
        Some(shading) => {
            let at = shading.colour_addr as usize;
            let area = layout.params.ls_shading as usize + SHADE_STATS_OFFSET;
            let counters = spus
                .iter()
                .map(|spu| {
                    // The PPE reads the counters from each SPE's memory-mapped local store.
                    ShadeCounters::from_be_bytes(spu.ls().get(area..).unwrap_or_default())
                })
                .collect();
            (
                Some(memory.bytes()[at..at + shading.colour_len].to_vec()),
                counters,
            )
        }
        _ => (None, Vec::new()),
    };
    let (reflect_counters, bounce_hits) = match layout.shading.as_ref().map(|s| (s, &s.reflect)) {
        Some((shading, Some(r))) => {
            let mut counters = vec![
                crate::kernel_abi::ReflectCounters::default();
                shading.block.reflect_depth as usize
            ];
            let area = layout.params.ls_shading as usize
                + crate::kernel_abi::REFLECT_AREA
                + crate::kernel_abi::REFLECT_COUNTERS_OFFSET;
            let size = std::mem::size_of::<crate::kernel_abi::ReflectCounters>();
            for spu in &spus {
                for (k, total) in counters.iter_mut().enumerate() {
                    let at = area + k * size;
                    total.add(&crate::kernel_abi::ReflectCounters::from_be_bytes(
                        spu.ls().get(at..at + size).unwrap_or_default(),
                    ));
                }
            }
            let at = r.hits_addr as usize;
            (counters, Some(memory.bytes()[at..at + r.hits_len].to_vec()))
        }
        _ => (Vec::new(), None),
    };
    let traffic = regions
        .iter()
        .enumerate()
        .map(|(i, (name, _, _))| {
            let read = spus.iter().map(|s| s.traffic().read[i]).sum();
            let written = spus.iter().map(|s| s.traffic().written[i]).sum();
            (name.clone(), read, written)
        })
        .collect();
    // The frame buffer ends main memory: taken out of it, moved down rather than copied
    // into fresh pages (a 1024x1024 frame's is 12 MB).
    let mut frame_buffer = system.into_memory().into_bytes();
    frame_buffer.truncate(fb + layout.frame_buffer_len);
    frame_buffer.drain(..fb);
    Ok(FrameRun {
        traffic,
        colour_buffer,
        shade_counters,
        shadow_rays,
        reflect_counters,
        bounce_hits,
        events,
        frame_buffer,
        frame_cycles: spus_report.iter().map(|s| s.cycles).max().unwrap_or(0),
        profile,
        symbols: program.symbols.clone(),
        kernel_image: program.image.clone(),
        config: KernelConfig::new(layout, frame.timing.dma_latency_ns),
        jit: {
            // This frame's compiling only, where the cache is older than the frame.
            let all = code.stats();
            spu_isa::jit::JitStats {
                blocks: all.blocks.saturating_sub(compiled_before.blocks),
                block_instructions: all
                    .block_instructions
                    .saturating_sub(compiled_before.block_instructions),
                compile_seconds: all.compile_seconds - compiled_before.compile_seconds,
                compiled_instructions: spus_report.iter().map(|s| s.compiled_instructions).sum(),
                ..all
            }
        },
        spus: spus_report,
    })
}
