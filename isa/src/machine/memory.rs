//! Main memory shared by all SPUs and the quantum boundary that publishes their writes:
//! the logged writes applied in simulated-time order, `putllc` outcomes, lost
//! reservations, and the shared memory interface's traffic settled.

use super::channels::event;
use super::mfc::{LoggedWrite, WriteKind};
use super::spu::Spu;

/// Main memory shared by all SPUs, big-endian bytes owned by the host, and the chip's
/// memory interface in front of it.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MainMemory {
    bytes: Vec<u8>,
    /// The cycle (fractional) at which the memory interface has moved every byte the SPUs'
    /// DMA commands asked for up to the last quantum boundary (see [`apply_quantum`]).
    bus_busy_until: f64,
    /// The same for the memory interface's EIB port, reads and writes.
    port_busy_until: [f64; 2],
}

/// A DMA transfer's claim on the memory interface, logged by the SPU that issued it for
/// the quantum's boundary to queue.
#[derive(Clone, Copy, Debug)]
pub(super) struct BusRequest {
    /// The first cycle its bytes may move (issue plus latency).
    pub(super) earliest: u64,
    pub(super) bytes: u32,
    /// Towards main memory (a put or a signal), else from it.
    pub(super) write: bool,
}

impl MainMemory {
    /// Main memory holding `bytes` (effective address 0 is the first byte), with an idle memory interface.
    pub fn new(bytes: Vec<u8>) -> Self {
        MainMemory {
            bytes,
            bus_busy_until: 0.0,
            port_busy_until: [0.0; 2],
        }
    }
    /// Main memory of `len` zero bytes.
    pub fn zeroed(len: usize) -> Self {
        MainMemory::new(vec![0; len])
    }

    /// The bytes, given up (a large result taken out without a copy).
    pub fn into_bytes(self) -> Vec<u8> {
        self.bytes
    }

    /// The cycle at which the memory interface has drained the traffic published so far.
    pub fn bus_busy_until(&self) -> u64 {
        self.bus_busy_until.ceil() as u64
    }
    /// Size of main memory in bytes.
    pub fn len(&self) -> usize {
        self.bytes.len()
    }
    /// Whether main memory has no bytes.
    pub fn is_empty(&self) -> bool {
        self.bytes.is_empty()
    }
    /// The whole of main memory, indexed by effective address.
    pub fn bytes(&self) -> &[u8] {
        &self.bytes
    }
    /// The whole of main memory, writable (for the host to set up inputs).
    pub fn bytes_mut(&mut self) -> &mut [u8] {
        &mut self.bytes
    }
    /// The big-endian word at effective address `addr`, or 0 if it is not all inside main memory.
    pub fn read_u32(&self, addr: u32) -> u32 {
        let a = addr as usize;
        self.bytes
            .get(a..a + 4)
            .map(|b| u32::from_be_bytes([b[0], b[1], b[2], b[3]]))
            .unwrap_or(0)
    }
    /// Writes `value` big-endian at effective address `addr`; ignored if it is not all inside main memory.
    pub fn write_u32(&mut self, addr: u32, value: u32) {
        let a = addr as usize;
        if let Some(b) = self.bytes.get_mut(a..a + 4) {
            b.copy_from_slice(&value.to_be_bytes());
        }
    }
    /// The big-endian single-precision float at effective address `addr` (0.0 outside main memory).
    pub fn read_f32(&self, addr: u32) -> f32 {
        f32::from_bits(self.read_u32(addr))
    }
    /// Writes `value` as a big-endian single-precision float at `addr`; ignored outside main memory.
    pub fn write_f32(&mut self, addr: u32, value: f32) {
        self.write_u32(addr, value.to_bits())
    }
    /// `len` bytes from `addr`, or `None` if they are not all inside main memory.
    pub fn read_bytes(&self, addr: u64, len: usize) -> Option<&[u8]> {
        let end = addr.checked_add(len as u64)?;
        self.bytes.get(addr as usize..usize::try_from(end).ok()?)
    }
    /// Writes `data` at `addr`; false (and nothing written) if it does not fit.
    pub fn write_bytes(&mut self, addr: u64, data: &[u8]) -> bool {
        let Some(end) = addr.checked_add(data.len() as u64) else {
            return false;
        };
        match usize::try_from(end)
            .ok()
            .and_then(|end| self.bytes.get_mut(addr as usize..end))
        {
            Some(dst) => {
                dst.copy_from_slice(data);
                true
            }
            None => false,
        }
    }
    pub(super) fn range(&self, ea: u64, size: u32) -> Option<std::ops::Range<usize>> {
        let end = ea.checked_add(size as u64)?;
        (end <= self.bytes.len() as u64).then_some(ea as usize..end as usize)
    }
}

/// The chip's memory interface (25.6 GB/s at 2.4 GHz, 10.67 bytes per cycle) serves the
/// DMA commands of all SPUs first come, first served, and so does its EIB port (16 bytes
/// per bus cycle in each direction, 8 per core cycle): at a boundary the commands of the
/// quantum just run, ordered by (first cycle they may move data, SPU index, order), are
/// queued behind the earlier traffic, and every SPU's later commands complete no earlier
/// than the interface and the port can serve them behind it. Commands of one quantum do
/// not delay each other across SPUs (each SPU's own engine, 8 bytes per cycle, still
/// does): sharing takes effect one quantum late, and the outcome depends only on simulated
/// time (`docs/memory-model.md`). One SPU alone never waits for it (8 <= 8 < 10.67).
fn settle_memory_bus(spus: &mut [Spu], memory: &mut MainMemory) {
    let mut traffic: Vec<(u64, usize, usize, BusRequest)> = Vec::new();
    for (i, spu) in spus.iter_mut().enumerate() {
        for (k, request) in spu.bus_log.drain(..).enumerate() {
            traffic.push((request.earliest, i, k, request));
        }
    }
    let Some(first) = spus.first() else {
        return;
    };
    let chip = first.timing_config.chip_bytes_per_cycle();
    let port = first.timing_config.eib_port_bytes_per_cycle;
    traffic.sort_unstable_by_key(|(earliest, i, k, _)| (*earliest, *i, *k));
    let mut busy = memory.bus_busy_until;
    let mut port_busy = memory.port_busy_until;
    for (earliest, _, _, request) in traffic {
        busy = busy.max(earliest as f64) + request.bytes as f64 / chip;
        let way = &mut port_busy[request.write as usize];
        *way = way.max(earliest as f64) + request.bytes as f64 / port;
    }
    memory.bus_busy_until = busy;
    memory.port_busy_until = port_busy;
    for spu in spus.iter_mut() {
        spu.bus_free_at = busy.ceil() as u64;
        spu.port_free_at = port_busy.map(|b| b.ceil() as u64);
    }
}

/// Applies every SPU's logged main-memory writes in (cycle, SPU index, sequence) order and
/// settles `putllc` outcomes and lost reservations (see the module docs).
pub fn apply_quantum(spus: &mut [Spu], memory: &mut MainMemory) {
    let mut all: Vec<(u64, usize, u64, LoggedWrite)> = Vec::new();
    for (i, spu) in spus.iter_mut().enumerate() {
        for w in spu.writes.drain(..) {
            all.push((w.cycle, i, w.seq, w));
        }
    }
    all.sort_by_key(|(c, i, s, _)| (*c, *i, *s));
    settle_memory_bus(spus, memory);
    for (_, i, _, w) in all {
        if let WriteKind::Signal { spu, which } = w.kind {
            // A signal for an SPU that is not running here goes nowhere.
            let value = u32::from_be_bytes([w.data[0], w.data[1], w.data[2], w.data[3]]);
            if let Some(target) = spus.iter_mut().find(|s| s.index == spu) {
                target.write_signal(which as usize, value);
            }
            continue;
        }
        let line = w.ea & !127;
        let apply = match w.kind {
            WriteKind::Conditional => {
                let ok = spus[i].reservation == Some(line);
                spus[i].reservation = None;
                spus[i].atomic_pending = false;
                spus[i].atomic_stat = Some((if ok { 0 } else { 1 }, 0));
                ok
            }
            _ => true,
        };
        if !apply {
            continue;
        }
        let start = w.ea as usize;
        if let Some(dst) = memory.bytes.get_mut(start..start + w.data.len()) {
            dst.copy_from_slice(&w.data);
        }
        let first_line = w.ea & !127;
        let last_line = (w.ea + w.data.len().max(1) as u32 - 1) & !127;
        for (j, other) in spus.iter_mut().enumerate() {
            if j == i {
                continue;
            }
            if let Some(r) = other.reservation {
                if r >= first_line && r <= last_line {
                    other.reservation = None;
                    other.event_status |= event::LR;
                }
            }
        }
    }
}
