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
    let Some(first) = spus.first() else {
        return;
    };
    let chip = first.timing_config.chip_bytes_per_cycle();
    let port = first.timing_config.eib_port_bytes_per_cycle;
    let mut busy = memory.bus_busy_until;
    let mut port_busy = memory.port_busy_until;
    // The queue is a fold in floating point, so its order is kept exactly; each SPU's
    // log is already in issue order, so merging the logs costs less than sorting them all.
    let logs: Vec<&mut Vec<BusRequest>> = spus.iter_mut().map(|s| &mut s.bus_log).collect();
    in_order(
        logs,
        |r| r.earliest,
        |_, request| {
            busy = busy.max(request.earliest as f64) + request.bytes as f64 / chip;
            let way = &mut port_busy[request.write as usize];
            *way = way.max(request.earliest as f64) + request.bytes as f64 / port;
        },
    );
    memory.bus_busy_until = busy;
    memory.port_busy_until = port_busy;
    for spu in spus.iter_mut() {
        spu.bus_free_at = busy.ceil() as u64;
        spu.port_free_at = port_busy.map(|b| b.ceil() as u64);
    }
}

/// Hands `visit` every entry of the SPUs' logs (`logs[i]` is SPU `i`'s, in the order it
/// logged them) in (`cycle`, SPU index, order in its log) order, the order a sort of all
/// entries by that key gives, and empties the logs (keeping their room for the next
/// quantum). A log is nearly always in cycle order already; one that is not is first
/// sorted stably on its own. The logs are then merged through a heap of their heads (one
/// per SPU), which costs each entry a few comparisons instead of a sort of all entries;
/// one log alone needs neither.
fn in_order<T>(
    mut logs: Vec<&mut Vec<T>>,
    cycle: impl Fn(&T) -> u64,
    mut visit: impl FnMut(usize, T),
) {
    use std::cmp::Reverse;
    use std::collections::BinaryHeap;
    for log in logs.iter_mut() {
        if !log.is_sorted_by_key(&cycle) {
            log.sort_by_key(&cycle);
        }
    }
    let mut logging = (0..logs.len()).filter(|&i| !logs[i].is_empty());
    match (logging.next(), logging.next()) {
        (None, _) => return,
        (Some(i), None) => {
            // One SPU logged anything (always so with one SPU): its log is the order.
            logs[i].drain(..).for_each(|e| visit(i, e));
            return;
        }
        _ => {}
    }
    let mut heads = BinaryHeap::with_capacity(logs.len());
    let mut entries = Vec::with_capacity(logs.len());
    for (i, log) in logs.iter_mut().enumerate() {
        if let Some(first) = log.first() {
            heads.push(Reverse((cycle(first), i)));
        }
        entries.push(log.drain(..));
    }
    while let Some(mut head) = heads.peek_mut() {
        let i = head.0 .1;
        let entry = entries[i].next().expect("a head has an entry");
        match entries[i].as_slice().first() {
            Some(next) => head.0 .0 = cycle(next),
            None => {
                std::collections::binary_heap::PeekMut::pop(head);
            }
        }
        visit(i, entry);
    }
}

/// Applies every SPU's logged main-memory writes in (cycle, SPU index, sequence) order and
/// settles `putllc` outcomes and lost reservations (see the module docs).
pub fn apply_quantum(spus: &mut [Spu], memory: &mut MainMemory) {
    if spus.iter().all(|s| s.writes.is_empty()) {
        // Nearly half of a 16-SPE frame's quanta (docs/parallel.md): no log to take out.
        settle_memory_bus(spus, memory);
        return;
    }
    // Taken out, so that applying them may change any SPU; given back empty, with their room.
    let mut logs: Vec<Vec<LoggedWrite>> = spus
        .iter_mut()
        .map(|s| std::mem::take(&mut s.writes))
        .collect();
    settle_memory_bus(spus, memory);
    // A reservation is only ever lost here, so those who hold one now are all who can lose it.
    let holders: Vec<usize> = (0..spus.len())
        .filter(|&j| spus[j].reservation.is_some())
        .collect();
    in_order(
        logs.iter_mut().collect(),
        |w| w.cycle,
        |i, w| {
            if let WriteKind::Signal { spu, which } = w.kind {
                // A signal for an SPU that is not running here goes nowhere.
                let value = u32::from_be_bytes([w.data[0], w.data[1], w.data[2], w.data[3]]);
                if let Some(target) = spus.iter_mut().find(|s| s.index == spu) {
                    target.write_signal(which as usize, value);
                }
                return;
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
                return;
            }
            let start = w.ea as usize;
            if let Some(dst) = memory.bytes.get_mut(start..start + w.data.len()) {
                dst.copy_from_slice(&w.data);
            }
            let first_line = w.ea & !127;
            let last_line = (w.ea + w.data.len().max(1) as u32 - 1) & !127;
            for &j in &holders {
                if j == i {
                    continue;
                }
                let other = &mut spus[j];
                if let Some(r) = other.reservation {
                    if r >= first_line && r <= last_line {
                        other.reservation = None;
                        other.event_status |= event::LR;
                    }
                }
            }
        },
    );
    for (spu, log) in spus.iter_mut().zip(logs) {
        spu.writes = log;
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use proptest::prelude::*;

    proptest! {
        /// The merge of the logs visits exactly what a sort of all entries by (cycle, SPU,
        /// place in its log) gives, with ties of cycle within and across logs, logs out of
        /// cycle order and empty logs; and leaves every log empty.
        #[test]
        fn logs_are_visited_in_the_order_a_sort_of_all_gives(
            cycles in prop::collection::vec(prop::collection::vec(0u64..6, 0..8), 0..6)
        ) {
            let mut logs: Vec<Vec<(u64, usize)>> = cycles
                .iter()
                .map(|log| log.iter().enumerate().map(|(k, &c)| (c, k)).collect())
                .collect();
            let mut expected: Vec<(usize, (u64, usize))> = logs
                .iter()
                .enumerate()
                .flat_map(|(i, log)| log.iter().map(move |&e| (i, e)))
                .collect();
            expected.sort_by_key(|&(i, (c, k))| (c, i, k));
            let mut visited = Vec::new();
            in_order(logs.iter_mut().collect(), |e| e.0, |i, e| visited.push((i, e)));
            prop_assert_eq!(visited, expected);
            prop_assert!(logs.iter().all(Vec::is_empty));
        }
    }
}
