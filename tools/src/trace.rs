//! `spu render --trace FILE.json`: the frame over simulated time in the Trace Event Format
//! (the JSON that Perfetto and chrome://tracing open as is): per SPU a track of its tiles,
//! one of its packets and one of its channel (DMA) waits; per-SPU counters of the share of
//! time waiting; and a counter of the shared memory interface's load.

use serde::Serialize;
use spu_loader::timeline::Timeline;
use std::collections::BTreeMap;

/// One event; absent fields are left out of the JSON.
#[derive(Clone, Debug, Serialize)]
pub struct TraceEvent {
    pub name: String,
    #[serde(skip_serializing_if = "str::is_empty")]
    pub cat: &'static str,
    pub ph: &'static str,
    /// Microseconds of simulated time.
    pub ts: f64,
    #[serde(skip_serializing_if = "Option::is_none")]
    pub dur: Option<f64>,
    pub pid: u32,
    pub tid: u32,
    #[serde(skip_serializing_if = "serde_json::Map::is_empty")]
    pub args: serde_json::Map<String, serde_json::Value>,
}

#[derive(Clone, Debug, Serialize)]
#[serde(rename_all = "camelCase")]
pub struct Trace {
    pub trace_events: Vec<TraceEvent>,
    pub display_time_unit: &'static str,
}

/// Track ids: SPU `i`'s packets on `i`, its tiles on `TILE_TRACKS + i` (with software
/// hyperthreading a tile's packets straddle the next tile's take), its waits on
/// `WAIT_TRACKS + i`.
const WAIT_TRACKS: u32 = 100;
const TILE_TRACKS: u32 = 200;
/// Cycles per sample of the memory interface counter.
const LOAD_BUCKET: u64 = 10_000;

fn args(pairs: &[(&str, serde_json::Value)]) -> serde_json::Map<String, serde_json::Value> {
    pairs
        .iter()
        .map(|(k, v)| (k.to_string(), v.clone()))
        .collect()
}

/// The trace of a frame at `clock_ghz`.
pub fn trace(timeline: &Timeline, spes: usize, clock_ghz: f64) -> Trace {
    let us = |cycles: u64| cycles as f64 / (clock_ghz * 1e3);
    let mut ev = Vec::new();
    let meta = |name: &str, tid: u32, a| TraceEvent {
        name: name.into(),
        cat: "",
        ph: "M",
        ts: 0.0,
        dur: None,
        pid: 0,
        tid,
        args: a,
    };
    ev.push(meta(
        "process_name",
        0,
        args(&[("name", "simulated Cell BE".into())]),
    ));
    for spu in 0..spes as u32 {
        for (tid, name, order) in [
            (TILE_TRACKS + spu, format!("SPU {spu} tiles"), 3 * spu),
            (spu, format!("SPU {spu} packets"), 3 * spu + 1),
            (
                WAIT_TRACKS + spu,
                format!("SPU {spu} DMA waits"),
                3 * spu + 2,
            ),
        ] {
            ev.push(meta("thread_name", tid, args(&[("name", name.into())])));
            ev.push(meta(
                "thread_sort_index",
                tid,
                args(&[("sort_index", order.into())]),
            ));
        }
    }
    let slice = |name: String, cat, tid, start: u64, end: u64, a| TraceEvent {
        name,
        cat,
        ph: "X",
        ts: us(start),
        dur: Some(us(end.saturating_sub(start))),
        pid: 0,
        tid,
        args: a,
    };
    let mut newest: BTreeMap<usize, u32> = BTreeMap::new();
    for t in &timeline.tiles {
        // with SHT, the span after an SPU's last take only finishes earlier tiles
        let finishing = newest.get(&t.spu).is_some_and(|&n| t.tile <= n);
        newest.insert(t.spu, t.tile);
        ev.push(slice(
            if finishing {
                format!("finishing tile {}", t.tile)
            } else {
                format!("tile {}", t.tile)
            },
            "tile",
            TILE_TRACKS + t.spu as u32,
            t.start,
            t.end,
            args(&[("cycles", (t.end - t.start).into())]),
        ));
    }
    for p in &timeline.packets {
        let (x, y) = timeline.packet_origin(p.tile, p.packet);
        ev.push(slice(
            format!("packet {}.{}", p.tile, p.packet),
            "packet",
            p.spu as u32,
            p.start,
            p.end,
            args(&[
                ("cycles", (p.end - p.start).into()),
                ("wait_cycles", p.wait.into()),
                ("x", x.into()),
                ("y", y.into()),
            ]),
        ));
    }
    for w in &timeline.waits {
        ev.push(slice(
            format!("wait ch{}", w.channel),
            "dma-wait",
            WAIT_TRACKS + w.spu as u32,
            w.start,
            w.end,
            args(&[
                ("channel", w.channel.into()),
                ("cycles", (w.end - w.start).into()),
            ]),
        ));
    }
    let counter = |name: String, cycle: u64, key: &str, value: f64| TraceEvent {
        name,
        cat: "",
        ph: "C",
        ts: us(cycle),
        dur: None,
        pid: 0,
        tid: 0,
        args: args(&[(key, value.into())]),
    };
    // per SPU: the share of each bucket's cycles spent waiting on a channel
    let mut waiting: BTreeMap<(usize, u64), u64> = BTreeMap::new();
    for w in &timeline.waits {
        spread(w.start, w.end, |bucket, cycles| {
            *waiting.entry((w.spu, bucket)).or_default() += cycles
        });
    }
    let end = timeline
        .packets
        .iter()
        .map(|p| p.end)
        .chain(timeline.waits.iter().map(|w| w.end))
        .max()
        .unwrap_or(0);
    for spu in 0..spes {
        for bucket in 0..=end / LOAD_BUCKET + 1 {
            let cycles = waiting.get(&(spu, bucket)).copied().unwrap_or(0);
            ev.push(counter(
                format!("SPU {spu} waiting on DMA"),
                bucket * LOAD_BUCKET,
                "%",
                (1000.0 * cycles as f64 / LOAD_BUCKET as f64).round() / 10.0,
            ));
        }
    }
    // the memory interface: bytes moved per bucket, spread over each transfer's time
    let mut load: BTreeMap<u64, f64> = BTreeMap::new();
    for t in &timeline.transfers {
        let (a, b) = (t.issue, t.complete.max(t.issue + 1));
        let per_cycle = t.bytes as f64 / (b - a) as f64;
        spread(a, b, |bucket, cycles| {
            *load.entry(bucket).or_default() += per_cycle * cycles as f64
        });
    }
    for bucket in 0..=end / LOAD_BUCKET + 1 {
        let bytes = load.get(&bucket).copied().unwrap_or(0.0);
        // bytes per cycle at `clock_ghz` GHz is GB/s
        let gbs = bytes / LOAD_BUCKET as f64 * clock_ghz;
        ev.push(counter(
            "memory interface".into(),
            bucket * LOAD_BUCKET,
            "GB/s",
            (gbs * 1000.0).round() / 1000.0,
        ));
    }
    ev.sort_by(|a, b| {
        (a.ph != "M", a.ts)
            .partial_cmp(&(b.ph != "M", b.ts))
            .unwrap()
    });
    Trace {
        trace_events: ev,
        display_time_unit: "ns",
    }
}

/// Calls `add(bucket, cycles)` for the cycles of `start..end` in each bucket.
fn spread(start: u64, end: u64, mut add: impl FnMut(u64, u64)) {
    let mut c = start;
    while c < end {
        let bucket = c / LOAD_BUCKET;
        let next = ((bucket + 1) * LOAD_BUCKET).min(end);
        add(bucket, next - c);
        c = next;
    }
}

/// The trace as JSON text.
pub fn to_json(trace: &Trace) -> String {
    serde_json::to_string(trace).expect("plain data serialises")
}
