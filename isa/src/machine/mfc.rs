//! The SPU's memory flow controller: DMA commands and lists, their timing on the SPU's DMA
//! engine and the shared memory interface, the atomic commands (`getllar`, `putllc`,
//! `putlluc`) and `sndsig`. Main-memory writes are logged for [`super::apply_quantum`].

use super::channels::{event, ChannelOutcome};
use super::memory::MainMemory;
use super::spu::Spu;
use crate::machine::exec::LS_MASK;

#[derive(Clone, Debug)]
pub(super) struct DmaCommand {
    pub(super) tag: u8,
    pub(super) complete: u64,
    /// Bytes to copy into local store at completion (gets).
    pub(super) incoming: Vec<(u32, Vec<u8>)>,
}

#[derive(Clone, Debug)]
pub(super) enum WriteKind {
    Put,
    Conditional,
    Unconditional,
    /// A `sndsig` to signal-notification register `which` (0 or 1) of the SPU whose
    /// index is `spu`.
    Signal {
        spu: u32,
        which: u8,
    },
}

/// Where `sndsig` finds the other SPUs' signal-notification registers: the PlayStation 3's
/// raw-SPU map (each SPU's problem-state area at `RAW_SPU_BASE + index * RAW_SPU_STRIDE +
/// PROBLEM_STATE_OFFSET`), with SPU_Sig_Notify_1 and _2 at their problem-state offsets
/// 0x1400C and 0x1C00C (Cell BE Handbook, problem-state register map).
pub const RAW_SPU_BASE: u32 = 0xE000_0000;
/// Bytes between consecutive raw SPUs' areas.
pub const RAW_SPU_STRIDE: u32 = 0x10_0000;
/// Offset of the problem-state registers within a raw SPU's area, in bytes.
pub const PROBLEM_STATE_OFFSET: u32 = 0x4_0000;
/// Offsets of SPU_Sig_Notify_1 and _2 within the problem-state area, in bytes.
pub const SIG_NOTIFY_OFFSETS: [u32; 2] = [0x1_400C, 0x1_C00C];

/// The effective address of signal-notification register `which` (0 or 1) of the SPU with
/// index `spu`, for `sndsig`.
pub fn signal_notify_ea(spu: u32, which: usize) -> u32 {
    RAW_SPU_BASE + spu * RAW_SPU_STRIDE + PROBLEM_STATE_OFFSET + SIG_NOTIFY_OFFSETS[which & 1]
}

/// The SPU index and register a `sndsig` effective address names, if it names one.
fn signal_target(ea: u64) -> Option<(u32, u8)> {
    let off = ea.checked_sub(RAW_SPU_BASE as u64)?;
    let (spu, within) = (off / RAW_SPU_STRIDE as u64, off % RAW_SPU_STRIDE as u64);
    let which = SIG_NOTIFY_OFFSETS
        .iter()
        .position(|&o| within == (PROBLEM_STATE_OFFSET + o) as u64)?;
    (spu < 256).then_some((spu as u32, which as u8))
}

#[derive(Clone, Debug)]
pub(super) struct LoggedWrite {
    pub(super) cycle: u64,
    pub(super) ea: u32,
    pub(super) data: Vec<u8>,
    pub(super) kind: WriteKind,
}

/// The longest DMA latency in cycles (about a day at 3.2 GHz).
const MAX_DMA_LATENCY: u64 = 1 << 48;

impl Spu {
    /// The DMA latency in cycles. Configurations the tools refuse (an infinite clock, a
    /// NaN latency) still give a number the cycle arithmetic can saturate on, never wrap.
    pub(super) fn dma_latency(&self) -> u64 {
        let cycles = self.timing_config.dma_latency_ns * self.timing_config.clock_ghz;
        if cycles.is_nan() {
            0
        } else {
            cycles.round().clamp(0.0, MAX_DMA_LATENCY as f64) as u64
        }
    }

    pub(super) fn complete_dma(&mut self, now: u64) {
        let mut i = 0;
        while i < self.queue.len() {
            if self.queue[i].complete <= now {
                let cmd = self.queue.remove(i);
                for (lsa, bytes) in cmd.incoming {
                    for (k, b) in bytes.iter().enumerate() {
                        self.core.ls[(lsa as usize + k) & LS_MASK as usize] = *b;
                    }
                    self.redecode(lsa, bytes.len() as u32);
                }
            } else {
                i += 1;
            }
        }
        if let Some(mode) = self.tag_update {
            let done = self.tag_done_mask() & self.tag_mask;
            let satisfied = match mode {
                1 => done != 0 || self.tag_mask == 0,
                2 => done == self.tag_mask,
                _ => true,
            };
            if satisfied {
                self.event_status |= event::TAG_GROUP;
            }
        }
    }

    pub(super) fn busy_tags(&self) -> u32 {
        self.queue.iter().fold(0, |m, c| m | (1 << c.tag))
            | self.stalled_list.map_or(0, |s| 1 << s.0)
    }

    pub(super) fn tag_done_mask(&self) -> u32 {
        !self.busy_tags()
    }

    /// The cycle when the commands of the tags in `mask` complete (all) or the first does.
    pub(super) fn completion_of(&self, mask: u32, all: bool) -> Option<u64> {
        let times = self
            .queue
            .iter()
            .filter(|c| mask & (1 << c.tag) != 0)
            .map(|c| c.complete);
        if all {
            times.max()
        } else {
            times.min()
        }
    }

    /// The completion cycle of a transfer of `bytes` issued at `now` (`write`: to main
    /// memory), behind this SPU's earlier commands on its own engine and behind the traffic
    /// the memory interface and its EIB port still have from earlier quanta
    /// (`docs/memory-model.md`).
    pub(super) fn schedule(&mut self, now: u64, bytes: u32, write: bool) -> u64 {
        let earliest = now.saturating_add(self.dma_latency());
        let per_cycle = (self.timing_config.spu_bytes_per_cycle.max(1.0)) as u64;
        let own = earliest
            .max(self.dma_free_at)
            .saturating_add((bytes as u64).div_ceil(per_cycle));
        // Behind the traffic the memory interface still has from earlier quanta.
        let behind = |free_at: u64, rate: f64| {
            (earliest.max(free_at) as f64 + bytes as f64 / rate).ceil() as u64
        };
        let shared =
            behind(self.bus_free_at, self.timing_config.chip_bytes_per_cycle()).max(behind(
                self.port_free_at[write as usize],
                self.timing_config.eib_port_bytes_per_cycle,
            ));
        // A clock or bandwidth the tools refuse can make `shared` infinite: a transfer still
        // ends within the longest latency of a later start, never near the end of u64.
        let done = own
            .max(shared)
            .min(earliest.saturating_add(MAX_DMA_LATENCY));
        self.bus_log.push(super::memory::BusRequest {
            earliest,
            bytes,
            write,
        });
        self.dma_free_at = done;
        if let Some(t) = &mut self.timing {
            t.dma_local_store(done, bytes);
        }
        done
    }

    pub(super) fn check_transfer(
        &self,
        lsa: u32,
        ea: u64,
        size: u32,
        memory: &MainMemory,
    ) -> Result<(), String> {
        let ok_size = matches!(size, 1 | 2 | 4 | 8) || (size.is_multiple_of(16) && size <= 16384);
        if !ok_size {
            return Err(format!(
                "transfer size {size} is not 1, 2, 4, 8 or a multiple of 16 up to 16384"
            ));
        }
        if size == 0 {
            // A zero-length transfer moves nothing and completes its tag.
        } else if size < 16 {
            if !lsa.is_multiple_of(size) || !ea.is_multiple_of(size as u64) {
                return Err(format!(
                    "{size}-byte transfer with LS {lsa:#x} / EA {ea:#x} not naturally aligned"
                ));
            }
            if (lsa ^ ea as u32) & 15 != 0 {
                return Err(format!(
                    "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits"
                ));
            }
        } else if (lsa as u64 ^ ea) & 15 != 0 {
            return Err(format!(
                "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits for a {size}-byte transfer"
            ));
        }
        if memory.range(ea, size).is_none() {
            return Err(format!(
                "EA {ea:#x}+{size} is outside main memory ({} bytes)",
                memory.len()
            ));
        }
        Ok(())
    }

    pub(super) fn mfc_command(
        &mut self,
        cmd: u32,
        now: u64,
        memory: &MainMemory,
    ) -> ChannelOutcome {
        let tag = self.core.mfc.tag_id;
        self.dma_ctx = (
            cmd as u8,
            self.core.mfc.lsa,
            ((self.core.mfc.eah as u64) << 32) | self.core.mfc.eal as u64,
            self.core.mfc.size,
            tag,
        );
        if tag > 31 && !matches!(cmd, 0xd0 | 0xb4 | 0xb0 | 0xb8) {
            return ChannelOutcome::Error(format!("tag {tag} is out of range 0..31"));
        }
        let tag = (tag & 31) as u8;
        let lsa = self.core.mfc.lsa & LS_MASK;
        let ea = ((self.core.mfc.eah as u64) << 32) | self.core.mfc.eal as u64;
        match cmd {
            0x40..=0x42 | 0x20..=0x22 => {
                let size = self.core.mfc.size;
                if let Err(e) = self.check_transfer(lsa, ea, size, memory) {
                    return ChannelOutcome::Error(e);
                }
                let complete = self.schedule(now, size, cmd & 0x40 == 0);
                let range = memory.range(ea, size).unwrap();
                if cmd & 0x40 != 0 {
                    let data = self.read_main(memory, range);
                    self.queue.push(DmaCommand {
                        tag,
                        complete,
                        incoming: vec![(lsa, data)],
                    });
                } else {
                    let data = self.ls_bytes(lsa, size);
                    self.log_write(complete, ea as u32, data, WriteKind::Put);
                    self.queue.push(DmaCommand {
                        tag,
                        complete,
                        incoming: Vec::new(),
                    });
                }
                ChannelOutcome::Done
            }
            0x44..=0x46 | 0x24..=0x26 => {
                let list = self.core.mfc.eal & LS_MASK;
                if list & 7 != 0 {
                    return ChannelOutcome::Error(format!(
                        "DMA list address {list:#x} is not 8-byte aligned"
                    ));
                }
                if !self.core.mfc.size.is_multiple_of(8) || self.core.mfc.size / 8 > 2048 {
                    return ChannelOutcome::Error(format!(
                        "DMA list size {} is not a multiple of 8 up to 16384",
                        self.core.mfc.size
                    ));
                }
                self.run_list(
                    cmd as u8,
                    tag,
                    lsa,
                    list,
                    self.core.mfc.size / 8,
                    self.core.mfc.eah,
                    now,
                    memory,
                )
            }
            0xd0 => {
                let line = self.core.mfc.eal & !127;
                let ea = ((self.core.mfc.eah as u64) << 32) | line as u64;
                if lsa & 127 != 0 {
                    return ChannelOutcome::Error(format!(
                        "getllar LS {lsa:#x} not 128-byte aligned"
                    ));
                }
                let Some(range) = memory.range(ea, 128) else {
                    return ChannelOutcome::Error(format!(
                        "getllar EA {ea:#x} outside main memory"
                    ));
                };
                let data = self.read_main(memory, range);
                for (k, b) in data.iter().enumerate() {
                    self.core.ls[(lsa as usize + k) & LS_MASK as usize] = *b;
                }
                self.redecode(lsa, 128);
                self.reservation = Some(line);
                let ready = now.saturating_add(self.dma_latency());
                self.atomic_stat = Some((4, ready));
                ChannelOutcome::Done
            }
            0xb4 | 0xb0 | 0xb8 => {
                let line = self.core.mfc.eal & !127;
                if lsa & 127 != 0 {
                    return ChannelOutcome::Error(format!(
                        "putllc/putlluc LS {lsa:#x} not 128-byte aligned"
                    ));
                }
                if memory.range(line as u64, 128).is_none() {
                    return ChannelOutcome::Error(format!(
                        "atomic EA {line:#x} outside main memory"
                    ));
                }
                let data: Vec<u8> = (0..128)
                    .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                    .collect();
                let cycle = now.saturating_add(self.dma_latency());
                if cmd == 0xb4 {
                    if self.reservation != Some(line) {
                        self.atomic_stat = Some((1, cycle));
                    } else {
                        self.log_write(cycle, line, data, WriteKind::Conditional);
                        self.atomic_pending = true;
                        self.atomic_stat = None;
                    }
                } else {
                    self.log_write(cycle, line, data, WriteKind::Unconditional);
                    self.atomic_stat = Some((2, cycle));
                }
                ChannelOutcome::Done
            }
            0xa0..=0xa2 => {
                // sndsig, sndsigb, sndsigf: four bytes from local store into another SPU's
                // signal-notification register, delivered when the command completes
                // (at the quantum boundary that publishes it, like a put).
                let Some((spu, which)) = signal_target(ea) else {
                    return ChannelOutcome::Error(format!(
                        "sndsig to EA {ea:#x}, which is no SPU's signal-notification register"
                    ));
                };
                if self.core.mfc.size != 4 {
                    return ChannelOutcome::Error(format!(
                        "sndsig of {} bytes (a signal is 4 bytes)",
                        self.core.mfc.size
                    ));
                }
                if lsa & 15 != (ea as u32) & 15 {
                    return ChannelOutcome::Error(format!(
                        "LS {lsa:#x} and EA {ea:#x} differ in their low 4 bits"
                    ));
                }
                let complete = self.schedule(now, 4, true);
                let data: Vec<u8> = (0..4)
                    .map(|k| self.core.ls[((lsa + k) & LS_MASK) as usize])
                    .collect();
                self.log_write(complete, ea as u32, data, WriteKind::Signal { spu, which });
                self.queue.push(DmaCommand {
                    tag,
                    complete,
                    incoming: Vec::new(),
                });
                ChannelOutcome::Done
            }
            0xc0 | 0xc8 | 0xcc => ChannelOutcome::Done,
            other => ChannelOutcome::Error(format!("unknown MFC command {other:#x}")),
        }
    }

    #[allow(clippy::too_many_arguments)]
    pub(super) fn run_list(
        &mut self,
        cmd: u8,
        tag: u8,
        mut lsa: u32,
        mut list: u32,
        mut remaining: u32,
        eah: u32,
        now: u64,
        memory: &MainMemory,
    ) -> ChannelOutcome {
        let mut incoming = Vec::new();
        let mut last = now;
        while remaining > 0 {
            let e0 = u32::from_be_bytes(
                self.core.ls[list as usize..list as usize + 4]
                    .try_into()
                    .unwrap(),
            );
            let e1 = u32::from_be_bytes(
                self.core.ls[list as usize + 4..list as usize + 8]
                    .try_into()
                    .unwrap(),
            );
            let size = e0 & 0x7fff;
            let ea = ((eah as u64) << 32) | e1 as u64;
            self.dma_ctx = (cmd, lsa, ea, size, tag as u32);
            if let Err(e) = self.check_transfer(lsa, ea, size, memory) {
                return ChannelOutcome::Error(format!("list element at {list:#x}: {e}"));
            }
            last = self.schedule(now, size, cmd & 0x40 == 0);
            let range = memory.range(ea, size).unwrap();
            if cmd & 0x40 != 0 {
                incoming.push((lsa, self.read_main(memory, range)));
            } else {
                let data = self.ls_bytes(lsa, size);
                self.log_write(last, e1, data, WriteKind::Put);
            }
            lsa = (lsa + size.div_ceil(16) * 16) & LS_MASK;
            list = (list + 8) & LS_MASK;
            remaining -= 1;
            if e0 & 0x8000_0000 != 0 && remaining > 0 {
                self.stalled_list = Some((tag, cmd, lsa, list, remaining, eah));
                self.list_stall |= 1 << tag;
                self.event_status |= event::LIST_STALL;
                break;
            }
        }
        self.queue.push(DmaCommand {
            tag,
            complete: last,
            incoming,
        });
        ChannelOutcome::Done
    }

    /// Main memory as this SPU sees it: the state at the last boundary with its own
    /// logged writes (not yet applied) laid over it, in issue order. Conditional stores
    /// whose outcome the boundary has not decided yet are left out.
    pub(super) fn read_main(
        &mut self,
        memory: &MainMemory,
        range: std::ops::Range<usize>,
    ) -> Vec<u8> {
        self.traffic
            .count(range.start as u64, range.len() as u64, false);
        let mut data = memory.bytes()[range.clone()].to_vec();
        for w in &self.writes {
            if matches!(w.kind, WriteKind::Conditional) {
                continue;
            }
            let (ws, we) = (w.ea as usize, w.ea as usize + w.data.len());
            let (s, e) = (ws.max(range.start), we.min(range.end));
            if s < e {
                data[s - range.start..e - range.start].copy_from_slice(&w.data[s - ws..e - ws]);
            }
        }
        data
    }

    /// `size` bytes of local store from `lsa` on (wrapping at its end), for a put.
    fn ls_bytes(&self, lsa: u32, size: u32) -> Vec<u8> {
        let (from, size) = ((lsa & LS_MASK) as usize, size as usize);
        let ls = &self.core.ls;
        let first = size.min(ls.len() - from);
        let mut data = Vec::with_capacity(size);
        data.extend_from_slice(&ls[from..from + first]);
        data.extend_from_slice(&ls[..size - first]);
        data
    }

    pub(super) fn log_write(&mut self, cycle: u64, ea: u32, data: Vec<u8>, kind: WriteKind) {
        self.traffic.count(ea as u64, data.len() as u64, true);
        self.writes.push(LoggedWrite {
            cycle,
            ea,
            data,
            kind,
        });
    }
}

/// Bytes an SPU's MFC moved from and to named main-memory regions (the host names them,
/// e.g. the scene's node, triangle, vertex and material arrays and the frame buffer): the
/// per-region bandwidth of the paper's Table 6. Bytes outside every region are not counted.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Traffic {
    /// `(start, end)` effective addresses, end exclusive.
    pub regions: Vec<(u64, u64)>,
    /// Bytes read (gets) and written (puts) per region.
    pub read: Vec<u64>,
    /// Bytes written (puts) per region, in the order of `regions`.
    pub written: Vec<u64>,
}

impl Traffic {
    /// Counters for `regions` (`(start, end)` effective addresses, end exclusive), all zero.
    pub fn new(regions: Vec<(u64, u64)>) -> Traffic {
        let n = regions.len();
        Traffic {
            regions,
            read: vec![0; n],
            written: vec![0; n],
        }
    }

    fn count(&mut self, ea: u64, len: u64, write: bool) {
        for (i, &(start, end)) in self.regions.iter().enumerate() {
            let overlap = (ea + len).min(end).saturating_sub(ea.max(start));
            if overlap > 0 {
                if write {
                    self.written[i] += overlap;
                } else {
                    self.read[i] += overlap;
                }
            }
        }
    }
}
