//! The multi-SPE runtime: starts N simulated SPUs on a shared main memory, lets them take
//! tiles from the shared counter, and collects the frame buffer and the statistics.
//!

use crate::frame::FrameLayout;
use crate::kernel_abi::{KernelStats, STATS_BYTES};
use crate::layout::StagedScene;

/// What one SPU did in a frame.
#[derive(Clone, Debug, Default)]
pub struct SpuReport {
    pub cycles: u64,
    pub instructions: u64,
    pub tiles: u64,
    pub stats: KernelStats,
}

/// The outcome of one frame.
#[derive(Clone, Debug, Default)]
pub struct FrameRun {
    pub frame_buffer: Vec<u8>,
    pub frame_cycles: u64,
    pub spus: Vec<SpuReport>,
    /// The timing model's counters, merged over all SPUs.
    pub profile: Option<spu_isa::profile::Profile>,
    /// The kernel's symbols (to split the profile by code section).
    pub symbols: Vec<(String, u32)>,
    /// The kernel's local-store image (to tell its no-ops apart in the profile).
    pub kernel_image: Vec<u8>,
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

    fn symbol(&self, name: &str) -> Option<u32> {
        self.symbols
            .iter()
            .find(|(n, _)| n == name)
            .map(|(_, a)| *a)
    }

    /// CPI, instructions, cycles and stalls of the code between two kernel labels.
    pub fn section_json(&self, from: &str, to: &str) -> String {
        let (Some(profile), Some(a), Some(b)) = (&self.profile, self.symbol(from), self.symbol(to))
        else {
            return "null".into();
        };
        let r = profile.range_totals(a, b);
        // IBM's simulator counts nop, lnop and hints apart: the CPI without them is the
        // figure to compare, the pairing nops of scheduled code would flatter it
        let nops: u64 = profile
            .addresses()
            .filter(|(pc, _)| (a..b).contains(pc))
            .filter(|(pc, _)| {
                let word = self
                    .kernel_image
                    .get(*pc as usize..*pc as usize + 4)
                    .map_or(0, |w| u32::from_be_bytes([w[0], w[1], w[2], w[3]]));
                let op = spu_isa::codec::decode(word).op;
                use spu_isa::table::Op;
                spu_isa::analysis::is_nop(op) || matches!(op, Op::Hbr | Op::Hbra | Op::Hbrr)
            })
            .map(|(_, s)| s.executions)
            .sum();
        let names = ["dep", "branch", "hint", "dp", "chan", "fetch"];
        let stalls: Vec<String> = r
            .stall
            .iter()
            .zip(names)
            .map(|(v, n)| format!("\"{n}\": {v}"))
            .collect();
        let real = r.executions - nops.min(r.executions);
        format!(
            "{{\"from\": {from:?}, \"to\": {to:?}, \"instructions\": {}, \"instructions_without_nops\": {real}, \"cycles\": {}, \"cpi\": {:.3}, \"cpi_without_nops\": {:.3}, \"dual_issue_pct\": {:.1}, \"stalls\": {{{}}}}}",
            r.executions,
            r.cycles,
            r.cpi(),
            if real > 0 { r.cycles as f64 / real as f64 } else { 0.0 },
            // both halves of a pair count a dual issue: the share of cycles that issue two
            if r.cycles > 0 { 50.0 * r.dual as f64 / r.cycles as f64 } else { 0.0 },
            stalls.join(", ")
        )
    }
}

impl FrameRun {
    /// Statistics as JSON for `spu render --stats`.
    pub fn stats_json(
        &self,
        scene: &str,
        width: u32,
        height: u32,
        clock_ghz: f64,
        mrays_per_sec: f64,
        validation: Option<(usize, usize)>,
    ) -> String {
        let spus: Vec<String> = self
            .spus
            .iter()
            .map(|s| {
                format!(
                    "{{\"cycles\": {}, \"instructions\": {}, \"tiles\": {}}}",
                    s.cycles, s.instructions, s.tiles
                )
            })
            .collect();
        let validation = match validation {
            Some((pixels, mismatches)) => {
                format!(
                    ",\n  \"validation\": {{\"pixels\": {pixels}, \"mismatches\": {mismatches}}}"
                )
            }
            None => String::new(),
        };
        let k = self.kernel_stats();
        let per = |x: u64| {
            if k.packets > 0 {
                x as f64 / k.packets as f64
            } else {
                0.0
            }
        };
        let pct = |x: u64, of: u64| {
            if of > 0 {
                100.0 * x as f64 / of as f64
            } else {
                0.0
            }
        };
        let cycles_per_spu = self.spus.iter().map(|s| s.cycles).max().unwrap_or(0);
        let per_spu_mrays = if cycles_per_spu > 0 {
            (width as f64 * height as f64)
                / self.spus.len().max(1) as f64
                / (cycles_per_spu as f64 / (clock_ghz * 1e9))
                / 1e6
        } else {
            0.0
        };
        let lookups = if k.bvh_lookups > 0 {
            k.bvh_lookups
        } else {
            k.traversal_steps
        };
        let table2 = format!(
            "{{\"traversal_steps_per_packet\": {:.2}, \"pair_steps_per_packet\": {:.2}, \"triangle_tests_per_packet\": {:.2}, \"triangles_culled_per_packet\": {:.2}, \"early_exits_pct\": {:.1}, \"early_hits_pct\": {:.1}, \"bvh_cache_hit_pct\": {:.1}, \"bvh_cache_hit_per_node_pct\": {:.1}, \"triangle_cache_hit_pct\": {:.1}, \"mrays_per_sec_per_spu\": {:.2}}}",
            per(k.traversal_steps),
            per(lookups),
            per(k.triangle_tests),
            per(k.triangles_culled),
            pct(k.early_exits, k.traversal_steps),
            pct(k.early_hits, k.traversal_steps),
            100.0 - pct(k.bvh_cache_misses, lookups),
            100.0 - pct(k.bvh_cache_misses, k.traversal_steps),
            100.0 - pct(k.triangle_cache_misses, k.triangle_lookups),
            per_spu_mrays
        );
        let stalls = self
            .profile
            .as_ref()
            .map_or("null".to_string(), |p| p.totals.json());
        let traversal = self.section_json("trav", "leaf");
        let intersection = self.section_json("leaf", "packet_done");
        let extra = format!(
            ",\n  \"table2\": {table2},\n  \"traversal\": {traversal},\n  \"intersection\": {intersection},\n  \"totals\": {stalls}"
        );
        let validation = validation + &extra;
        format!(
            "{{\n  \"scene\": {scene:?},\n  \"width\": {width},\n  \"height\": {height},\n  \"clock_ghz\": {clock_ghz},\n  \"frame_cycles\": {},\n  \"rays\": {},\n  \"mrays_per_sec\": {mrays_per_sec:.3},\n  \"spus\": [{}]{validation}\n}}\n",
            self.frame_cycles,
            width as u64 * height as u64,
            spus.join(", ")
        )
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
    let opts = spu_asm::Options {
        virtual_files: crate::kernels::include_files(),
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

/// Simulated cycles each SPU runs between two synchronisations of main memory. Writes and
/// atomic updates become visible to other SPUs at these boundaries, in a fixed order, so a
/// frame's result does not depend on how the SPUs are spread over host threads.
pub const QUANTUM_CYCLES: u64 = 10_000;

/// Stop code of a kernel that finished its frame (`stop 0x2000`, exit status 0).
pub const STOP_DONE: u16 = 0x2000;

/// Renders one frame with `spes` SPUs on `threads` host threads; `progress` hears the
/// number of tiles taken so far.
#[allow(clippy::too_many_arguments)]
pub fn render_frame(
    staged: &StagedScene,
    layout: &FrameLayout,
    spes: usize,
    threads: usize,
    timing: &spu_isa::timing::TimingConfig,
    fill: bool,
    max_cycles: u64,
    progress: &mut dyn FnMut(u32, u32),
) -> Result<FrameRun, String> {
    use spu_isa::machine::{apply_quantum, MainMemory, Spu, StopReason};
    let (source, name) = crate::kernels::frame_program(fill);
    let program = assemble_kernel(source, name)?;
    let mut memory = MainMemory::new(layout.memory_image(staged));
    let mut spus: Vec<Spu> = (0..spes)
        .map(|i| {
            let mut spu = Spu::new(i as u32);
            spu.load_image(&program.image);
            spu.set_pc(program.entry);
            spu.set_reg(3, [i as u32, 0, 0, 0]);
            spu.set_reg(4, [layout.param_addr, 0, 0, 0]);
            if std::env::var_os("SPU_NO_TIMING").is_none() {
                spu.enable_timing(timing.clone());
            }
            spu
        })
        .collect();
    let mut finished: Vec<Option<u64>> = vec![None; spes];
    let threads = threads.clamp(1, spes);
    let mut until = 0u64;
    while finished.iter().any(|f| f.is_none()) {
        until += QUANTUM_CYCLES;
        if until > max_cycles {
            return Err(format!(
                "the frame did not finish within {max_cycles} cycles"
            ));
        }
        let memory_view = &memory;
        let mut outcomes: Vec<Option<StopReason>> = vec![None; spes];
        let per_thread = spes.div_ceil(threads);
        if threads == 1 {
            for ((spu, out), done) in spus.iter_mut().zip(outcomes.iter_mut()).zip(&finished) {
                if done.is_none() {
                    *out = spu.run_quantum(memory_view, until);
                }
            }
        } else {
            std::thread::scope(|scope| {
                for (spu_chunk, (out_chunk, done_chunk)) in spus.chunks_mut(per_thread).zip(
                    outcomes
                        .chunks_mut(per_thread)
                        .zip(finished.chunks(per_thread)),
                ) {
                    scope.spawn(move || {
                        for ((spu, out), done) in
                            spu_chunk.iter_mut().zip(out_chunk).zip(done_chunk)
                        {
                            if done.is_none() {
                                *out = spu.run_quantum(memory_view, until);
                            }
                        }
                    });
                }
            });
        }
        apply_quantum(&mut spus, &mut memory);
        for (i, outcome) in outcomes.into_iter().enumerate() {
            match outcome {
                None => {}
                Some(StopReason::Stop(code)) if code == STOP_DONE => {
                    if spus[i].read_outbound_mailbox() != Some(1) {
                        return Err(format!("SPU {i} stopped without its end-of-frame message"));
                    }
                    finished[i] = Some(spus[i].cycles());
                }
                Some(StopReason::Blocked { .. }) => {}
                Some(other) => return Err(format!("SPU {i} stopped: {other:?}")),
            }
        }
        let taken = memory
            .read_u32(layout.counter_addr)
            .min(layout.params.num_tiles);
        progress(taken, layout.params.num_tiles);
    }
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
    Ok(FrameRun {
        frame_buffer: memory.bytes()[fb..fb + layout.frame_buffer_len].to_vec(),
        frame_cycles: spus_report.iter().map(|s| s.cycles).max().unwrap_or(0),
        spus: spus_report,
        profile,
        symbols: program.symbols.clone(),
        kernel_image: program.image.clone(),
    })
}
