//! When each tile and packet of a frame was traced, recovered from the SPUs' event logs
//! without help from the kernel: an SPU puts each packet's 1 KiB result block to the frame
//! buffer (the address names the tile and packet) and takes each tile with an atomic
//! update of the shared counter. A packet's cycles run from the SPU's previous packet put
//! (or, for a tile's first packet, from the moment the tile's atomic update is known to
//! have succeeded) to its own put. A tile's span on an SPU runs from the start of its first
//! packet to the put of its last or the start of the next tile's first packet, whichever
//! comes first: with software hyperthreading (and the kernel's claim of the next tile a
//! couple of packets before the end of one) the last packets of a tile finish inside the
//! next one's span.

use crate::frame::FrameLayout;
use crate::kernel_abi::{PACKETS_PER_TILE, PACKET_BLOCK_BYTES, PACKET_SIZE, TILE_SIZE};
use crate::runtime::FrameRun;
use spu_isa::machine::{ch, SpuEvent};

/// The MFC's put command (and its fenced and barrier forms).
const PUTS: [u8; 3] = [0x20, 0x21, 0x22];
/// The atomic commands that take a tile: getllar, putllc, putlluc.
const ATOMICS: [u8; 3] = [0xd0, 0xb4, 0xb0];

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct PacketSpan {
    pub spu: usize,
    pub tile: u32,
    /// Index within the tile (row-major 8x8 packets).
    pub packet: u32,
    pub start: u64,
    pub end: u64,
    /// Cycles of the span spent waiting on a channel (DMA data, tag status).
    pub wait: u64,
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct TileSpan {
    pub spu: usize,
    pub tile: u32,
    pub start: u64,
    pub end: u64,
}

/// A channel wait of one SPU.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Wait {
    pub spu: usize,
    pub start: u64,
    pub end: u64,
    pub channel: u8,
}

/// A DMA transfer of one SPU: issued, completed, bytes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Transfer {
    pub spu: usize,
    pub issue: u64,
    pub complete: u64,
    pub bytes: u32,
}

#[derive(Clone, Debug, Default)]
pub struct Timeline {
    pub packets: Vec<PacketSpan>,
    pub tiles: Vec<TileSpan>,
    pub waits: Vec<Wait>,
    pub transfers: Vec<Transfer>,
    pub width: u32,
    pub height: u32,
}

impl Timeline {
    /// The spans of a frame rendered with the event log on.
    pub fn new(run: &FrameRun, layout: &FrameLayout, width: u32, height: u32) -> Timeline {
        let fb = layout.frame_buffer_addr as u64;
        let fb_end = fb + layout.frame_buffer_len as u64;
        let counter_line = layout.counter_addr as u64 & !127;
        let mut t = Timeline {
            width,
            height,
            ..Default::default()
        };
        for (spu, events) in run.events.iter().enumerate() {
            let mut mark = 0u64;
            let mut waited = 0u64;
            // this SPU's tile spans, in the order their first packets completed
            let mut spans: Vec<TileSpan> = Vec::new();
            for event in events {
                match *event {
                    SpuEvent::ChannelWait {
                        cycle,
                        until,
                        channel,
                    } => {
                        if channel == ch::RD_ATOMIC_STAT {
                            // the tile counter's update is known: the tile is taken now,
                            // and the next packet starts from here
                            mark = mark.max(until);
                            waited = 0;
                        } else {
                            waited += until.saturating_sub(cycle);
                        }
                        t.waits.push(Wait {
                            spu,
                            start: cycle,
                            end: until,
                            channel,
                        });
                    }
                    SpuEvent::Dma {
                        cycle,
                        complete,
                        cmd,
                        ea,
                        size,
                        ..
                    } => {
                        if size > 0 && !ATOMICS.contains(&cmd) {
                            t.transfers.push(Transfer {
                                spu,
                                issue: cycle,
                                complete,
                                bytes: size,
                            });
                        }
                        if cmd == 0xd0 && ea & !127 == counter_line {
                            // taking a tile: the wait for it belongs to no packet
                            mark = cycle;
                            waited = 0;
                        } else if PUTS.contains(&cmd) && (fb..fb_end).contains(&ea) {
                            let block = ((ea - fb) / PACKET_BLOCK_BYTES as u64) as u32;
                            let (tile, packet) =
                                (block / PACKETS_PER_TILE, block % PACKETS_PER_TILE);
                            t.packets.push(PacketSpan {
                                spu,
                                tile,
                                packet,
                                start: mark,
                                end: cycle,
                                wait: waited,
                            });
                            match spans.iter_mut().rev().find(|s| s.tile == tile) {
                                Some(span) => {
                                    span.start = span.start.min(mark);
                                    span.end = cycle;
                                }
                                None => spans.push(TileSpan {
                                    spu,
                                    tile,
                                    start: mark,
                                    end: cycle,
                                }),
                            }
                            mark = cycle;
                            waited = 0;
                        }
                    }
                }
            }
            // one track per SPU: a tile's span ends where the next one's begins
            for i in 1..spans.len() {
                spans[i - 1].end = spans[i - 1].end.min(spans[i].start);
            }
            t.tiles.extend(spans);
        }
        t
    }

    /// The pixels of a packet: (x0, y0) of its 8x8 block.
    pub fn packet_origin(&self, tile: u32, packet: u32) -> (u32, u32) {
        let tiles_x = self.width.div_ceil(TILE_SIZE);
        let per_row = TILE_SIZE / PACKET_SIZE;
        (
            (tile % tiles_x) * TILE_SIZE + (packet % per_row) * PACKET_SIZE,
            (tile / tiles_x) * TILE_SIZE + (packet / per_row) * PACKET_SIZE,
        )
    }

    /// A value per pixel (row-major), from a value per packet; pixels of no packet get
    /// `None`.
    pub fn per_pixel(&self, value: impl Fn(&PacketSpan) -> f64) -> Vec<Option<f64>> {
        let mut out = vec![None; (self.width * self.height) as usize];
        for p in &self.packets {
            let (x0, y0) = self.packet_origin(p.tile, p.packet);
            let v = value(p);
            for y in y0..(y0 + PACKET_SIZE).min(self.height) {
                for x in x0..(x0 + PACKET_SIZE).min(self.width) {
                    out[(y * self.width + x) as usize] = Some(v);
                }
            }
        }
        out
    }
}
