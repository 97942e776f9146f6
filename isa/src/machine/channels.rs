//! The SPU's channels: mailboxes, signal notification, the decrementer, events and the
//! channel instructions (`rdch`, `wrch`, `rchcnt`) that read and write them; MFC command
//! channels hand over to [`super::mfc`].

use super::memory::MainMemory;
use super::spu::Spu;
use crate::codec::Inst;
use crate::table::Op;

/// Channel numbers (SPU ISA / Cell BE Handbook).
pub mod ch {
    /// SPU_RdEventStat: read the pending events enabled by the mask (waits while there are none).
    pub const RD_EVENT_STAT: u8 = 0;
    /// SPU_WrEventMask: write which events SPU_RdEventStat reports.
    pub const WR_EVENT_MASK: u8 = 1;
    /// SPU_WrEventAck: write to clear pending event bits.
    pub const WR_EVENT_ACK: u8 = 2;
    /// SPU_RdSigNotify1: read (and clear) signal-notification register 1 (waits while it is empty).
    pub const RD_SIG_NOTIFY1: u8 = 3;
    /// SPU_RdSigNotify2: read (and clear) signal-notification register 2 (waits while it is empty).
    pub const RD_SIG_NOTIFY2: u8 = 4;
    /// SPU_WrDec: load the decrementer.
    pub const WR_DEC: u8 = 7;
    /// SPU_RdDec: read the decrementer.
    pub const RD_DEC: u8 = 8;
    /// MFC_WrMSSyncReq: request a multisource synchronisation.
    pub const WR_MS_SYNC_REQ: u8 = 9;
    /// SPU_RdEventMask: read back the event mask.
    pub const RD_EVENT_MASK: u8 = 11;
    /// MFC_RdTagMask: read back the tag-group query mask.
    pub const RD_TAG_MASK: u8 = 12;
    /// SPU_RdMachStat: read the machine status (here only the interrupt-enable bit).
    pub const RD_MACH_STAT: u8 = 13;
    /// SPU_WrSRR0: write the interrupt return address (SRR0).
    pub const WR_SRR0: u8 = 14;
    /// SPU_RdSRR0: read the interrupt return address (SRR0).
    pub const RD_SRR0: u8 = 15;
    /// MFC_LSA: the local-store byte address of the next MFC command.
    pub const LSA: u8 = 16;
    /// MFC_EAH: the high 32 bits of the next MFC command's effective address.
    pub const EAH: u8 = 17;
    /// MFC_EAL: the low 32 bits of the next MFC command's effective address.
    pub const EAL: u8 = 18;
    /// MFC_Size: the next MFC command's transfer size in bytes (list size for list commands).
    pub const SIZE: u8 = 19;
    /// MFC_TagID: the next MFC command's tag group (0 to 31).
    pub const TAG_ID: u8 = 20;
    /// MFC_Cmd: write an MFC command opcode to queue the command with the parameters above.
    pub const CMD: u8 = 21;
    /// MFC_WrTagMask: write the tag groups a tag-status query looks at (one bit per tag).
    pub const WR_TAG_MASK: u8 = 22;
    /// MFC_WrTagUpdate: request a tag-status update (immediate, any or all).
    pub const WR_TAG_UPDATE: u8 = 23;
    /// MFC_RdTagStat: read the tag-status update's result (waits until it is ready).
    pub const RD_TAG_STAT: u8 = 24;
    /// MFC_RdListStallStat: read the tag groups whose DMA lists are stalled on a stall-and-notify element.
    pub const RD_LIST_STALL_STAT: u8 = 25;
    /// MFC_WrListStallAck: resume the stalled DMA list of a tag group.
    pub const WR_LIST_STALL_ACK: u8 = 26;
    /// MFC_RdAtomicStat: read the outcome of the last atomic command (`getllar`, `putllc`, `putlluc`).
    pub const RD_ATOMIC_STAT: u8 = 27;
    /// SPU_WrOutMbox: write the outbound mailbox (one entry; waits while it is full).
    pub const WR_OUT_MBOX: u8 = 28;
    /// SPU_RdInMbox: read the inbound mailbox (four entries; waits while it is empty).
    pub const RD_IN_MBOX: u8 = 29;
    /// SPU_WrOutIntrMbox: write the outbound interrupt mailbox (one entry; waits while it is full).
    pub const WR_OUT_INTR_MBOX: u8 = 30;
}

/// Event bits of SPU_RdEventStat, SPU_WrEventMask and SPU_WrEventAck (the values of the
/// SDK's `spu_mfcio.h`).
pub mod event {
    /// Multisource synchronisation (accepted in the mask, never raised here).
    pub const MULTI_SRC_SYNC: u32 = 0x1000;
    /// Privileged attention (never raised here).
    pub const PRIV_ATTN: u32 = 0x800;
    /// Lock-line reservation lost.
    pub const LR: u32 = 0x400;
    /// Signal-notification register 1 received a signal.
    pub const SIGNAL1: u32 = 0x200;
    /// Signal-notification register 2 received a signal.
    pub const SIGNAL2: u32 = 0x100;
    /// The outbound mailbox became available (the host read it).
    pub const OUT_MBOX: u32 = 0x80;
    /// The outbound interrupt mailbox became available.
    pub const OUT_INTR_MBOX: u32 = 0x40;
    /// The decrementer went from 0 to -1.
    pub const DECREMENTER: u32 = 0x20;
    /// The inbound mailbox holds a value.
    pub const IN_MBOX: u32 = 0x10;
    /// The MFC command queue has a free slot (never raised here: a full queue stalls).
    pub const QUEUE_VACANCY: u32 = 0x8;
    /// A DMA list element with stall-and-notify completed.
    pub const LIST_STALL: u32 = 0x2;
    /// A tag-status update request (any/all) is satisfied.
    pub const TAG_GROUP: u32 = 0x1;
}

pub(super) enum ChannelOutcome {
    Done,
    /// Not ready before this cycle; retry then.
    WaitUntil(u64),
    /// Ready only after the next quantum boundary.
    WaitBoundary,
    /// Only the host can make it ready.
    Host,
    Never,
    /// No such channel in that direction.
    Invalid,
    Error(String),
}

impl Spu {
    /// Host side of the inbound mailbox (4 deep): false when full.
    pub fn write_inbound_mailbox(&mut self, value: u32) -> bool {
        if self.in_mbox.len() >= 4 {
            return false;
        }
        self.in_mbox.push_back(value);
        self.event_status |= event::IN_MBOX;
        true
    }

    /// Takes the value the SPU wrote to its outbound mailbox, as the host (PPE) would; `None` if it is empty.
    pub fn read_outbound_mailbox(&mut self) -> Option<u32> {
        let v = self.out_mbox.take();
        if v.is_some() {
            self.event_status |= event::OUT_MBOX;
        }
        v
    }

    /// Takes the value the SPU wrote to its outbound interrupt mailbox, as the host would; `None` if it is empty.
    pub fn read_outbound_interrupt_mailbox(&mut self) -> Option<u32> {
        let v = self.out_intr_mbox.take();
        if v.is_some() {
            self.event_status |= event::OUT_INTR_MBOX;
        }
        v
    }

    /// Entries waiting in the inbound mailbox (0..4).
    pub fn inbound_mailbox_len(&self) -> usize {
        self.in_mbox.len()
    }

    /// Pending events (SPU_RdEventStat before the mask).
    pub fn event_status(&self) -> u32 {
        self.event_status
    }

    /// The interrupt-enable bit (set by the E forms of the indirect branches, cleared by
    /// the D forms and when an interrupt is taken).
    pub fn interrupts_enabled(&self) -> bool {
        self.core.interrupts_enabled
    }

    /// SRR0: where `iret` returns to (SPU_WrSRR0 / SPU_RdSRR0; an interrupt sets it).
    pub fn srr0(&self) -> u32 {
        self.core.srr0
    }

    /// Host (or another SPU's `sndsig`) writes a signal-notification register (0 or 1).
    pub fn write_signal(&mut self, which: usize, value: u32) {
        let w = which & 1;
        self.signal[w] = Some(match (self.signal[w], self.signal_or_mode[w]) {
            (Some(old), true) => old | value,
            _ => value,
        });
        self.event_status |= if w == 0 {
            event::SIGNAL1
        } else {
            event::SIGNAL2
        };
    }

    /// Brings time-driven state up to `now`: completed DMA (and the tag-group event) and
    /// the decrementer event.
    pub(super) fn update_events(&mut self, now: u64) {
        self.complete_dma(now);
        if let Some(t) = self.dec_event_at {
            if t <= now {
                self.event_status |= event::DECREMENTER;
                self.dec_event_at = None;
            }
        }
    }

    pub(super) fn read_channel(&mut self, channel: u8, now: u64) -> Result<u32, ChannelOutcome> {
        use ch::*;
        self.update_events(now);
        Ok(match channel {
            RD_EVENT_STAT => {
                let pending = self.event_status & self.event_mask;
                if pending == 0 {
                    let dec = self
                        .dec_event_at
                        .filter(|_| self.event_mask & event::DECREMENTER != 0);
                    let dma = self.queue.iter().map(|c| c.complete).min();
                    let next = match (dma, dec) {
                        (Some(a), Some(b)) => Some(a.min(b)),
                        (a, b) => a.or(b),
                    };
                    return Err(match next {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None if self.atomic_pending => ChannelOutcome::WaitBoundary,
                        None if self.host_feeds => ChannelOutcome::Host,
                        None => ChannelOutcome::Never,
                    });
                }
                pending
            }
            RD_SIG_NOTIFY1 | RD_SIG_NOTIFY2 => {
                let w = (channel - RD_SIG_NOTIFY1) as usize;
                match self.signal[w].take() {
                    Some(v) => v,
                    None => {
                        return Err(if self.host_feeds {
                            ChannelOutcome::Host
                        } else {
                            ChannelOutcome::Never
                        })
                    }
                }
            }
            RD_DEC => self.dec_value.wrapping_sub(
                (now.saturating_sub(self.dec_written_at) / self.decrementer_cycles_per_tick.max(1))
                    as u32,
            ),
            RD_EVENT_MASK => self.event_mask,
            RD_TAG_MASK => self.tag_mask,
            // Bit 0: interrupts enabled (not in isolation mode: bit 1 clear).
            RD_MACH_STAT => self.core.interrupts_enabled as u32,
            RD_SRR0 => self.core.srr0,
            RD_TAG_STAT => {
                let Some(mode) = self.tag_update.take() else {
                    return Err(ChannelOutcome::Never);
                };
                let done = self.tag_done_mask() & self.tag_mask;
                let ready = match mode {
                    1 => done != 0 || self.tag_mask == 0,
                    2 => done == self.tag_mask,
                    _ => true,
                };
                if !ready {
                    self.tag_update = Some(mode);
                    return Err(match self.completion_of(self.tag_mask, mode == 2) {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None if self.stalled_list.is_some() => ChannelOutcome::Never,
                        None => ChannelOutcome::Never,
                    });
                }
                done
            }
            RD_LIST_STALL_STAT => {
                if self.list_stall == 0 {
                    return Err(match self.queue.iter().map(|c| c.complete).min() {
                        Some(t) => ChannelOutcome::WaitUntil(t),
                        None => ChannelOutcome::Never,
                    });
                }
                std::mem::take(&mut self.list_stall)
            }
            RD_ATOMIC_STAT => match self.atomic_stat {
                Some((value, ready)) if ready <= now => {
                    self.atomic_stat = None;
                    value
                }
                Some((_, ready)) => return Err(ChannelOutcome::WaitUntil(ready)),
                None if self.atomic_pending => return Err(ChannelOutcome::WaitBoundary),
                None => return Err(ChannelOutcome::Never),
            },
            RD_IN_MBOX => match self.in_mbox.pop_front() {
                Some(v) => v,
                None => {
                    return Err(if self.host_feeds {
                        ChannelOutcome::Host
                    } else {
                        ChannelOutcome::Never
                    })
                }
            },
            _ => 0,
        })
    }

    pub(super) fn channel_count(&mut self, channel: u8, now: u64) -> u32 {
        use ch::*;
        self.update_events(now);
        match channel {
            RD_IN_MBOX => self.in_mbox.len() as u32,
            WR_OUT_MBOX => self.out_mbox.is_none() as u32,
            WR_OUT_INTR_MBOX => self.out_intr_mbox.is_none() as u32,
            RD_SIG_NOTIFY1 | RD_SIG_NOTIFY2 => {
                self.signal[(channel - RD_SIG_NOTIFY1) as usize].is_some() as u32
            }
            CMD => 16 - self.queue.len().min(16) as u32,
            RD_TAG_STAT => match self.tag_update {
                Some(2) => (self.tag_done_mask() & self.tag_mask == self.tag_mask) as u32,
                Some(1) => (self.tag_done_mask() & self.tag_mask != 0) as u32,
                Some(_) => 1,
                None => 0,
            },
            RD_ATOMIC_STAT => matches!(self.atomic_stat, Some((_, r)) if r <= now) as u32,
            RD_LIST_STALL_STAT => (self.list_stall != 0) as u32,
            RD_EVENT_STAT => (self.event_status & self.event_mask != 0) as u32,
            _ => 1,
        }
    }

    pub(super) fn channel(&mut self, inst: Inst, now: u64, memory: &MainMemory) -> ChannelOutcome {
        let channel = inst.ra;
        // The SPU's channels and their directions (../shared/isa/README.md, "Channels").
        const READ: u128 = 1 << 0
            | 1 << 3
            | 1 << 4
            | 1 << 8
            | 1 << 11
            | 1 << 12
            | 1 << 13
            | 1 << 15
            | 1 << 24
            | 1 << 25
            | 1 << 27
            | 1 << 29;
        const WRITE: u128 =
            1 << 1 | 1 << 2 | 1 << 7 | 1 << 9 | 1 << 14 | 0xff << 16 | 1 << 26 | 1 << 28 | 1 << 30;
        let valid = match inst.op {
            Op::Rdch => READ,
            Op::Wrch => WRITE,
            _ => READ | WRITE,
        };
        if valid >> (channel & 127) & 1 == 0 {
            return ChannelOutcome::Invalid;
        }
        match inst.op {
            Op::Rdch => match self.read_channel(channel, now) {
                Ok(v) => {
                    self.core.regs[inst.rt as usize] = [v, 0, 0, 0];
                    ChannelOutcome::Done
                }
                Err(wait) => wait,
            },
            Op::Rchcnt => {
                let n = self.channel_count(channel, now);
                self.core.regs[inst.rt as usize] = [n, 0, 0, 0];
                ChannelOutcome::Done
            }
            _ => {
                let v = self.core.regs[inst.rt as usize][0];
                self.write_channel(channel, v, now, memory)
            }
        }
    }

    pub(super) fn write_channel(
        &mut self,
        channel: u8,
        v: u32,
        now: u64,
        memory: &MainMemory,
    ) -> ChannelOutcome {
        use ch::*;
        self.update_events(now);
        match channel {
            WR_EVENT_MASK => self.event_mask = v,
            WR_EVENT_ACK => self.event_status &= !v,
            WR_DEC => {
                self.dec_value = v;
                self.dec_written_at = now;
                let tick = self.decrementer_cycles_per_tick.max(1);
                self.dec_event_at = Some(now.saturating_add((v as u64 + 1).saturating_mul(tick)));
            }
            WR_SRR0 => self.core.srr0 = v,
            // (The core latches these itself: `execute` does not hand them over.)
            LSA..=TAG_ID => self.core.mfc.set(channel, v),
            WR_TAG_MASK => self.tag_mask = v,
            WR_TAG_UPDATE => self.tag_update = Some(v & 3),
            WR_LIST_STALL_ACK => {
                if let Some((tag, cmd, lsa, list, remaining, eah)) = self.stalled_list.take() {
                    if tag as u32 == (v & 31) {
                        return self.run_list(cmd, tag, lsa, list, remaining, eah, now, memory);
                    }
                    self.stalled_list = Some((tag, cmd, lsa, list, remaining, eah));
                }
            }
            CMD => {
                if self.queue.len() >= 16 {
                    let earliest = self.queue.iter().map(|c| c.complete).min().unwrap_or(now);
                    return ChannelOutcome::WaitUntil(earliest);
                }
                let outcome = self.mfc_command(v & 0xff, now, memory);
                if self.events.is_some() {
                    self.log_mfc_command(v as u8, now, &outcome);
                }
                return outcome;
            }
            WR_OUT_MBOX => {
                if self.out_mbox.is_some() {
                    return ChannelOutcome::Host;
                }
                self.out_mbox = Some(v);
            }
            WR_OUT_INTR_MBOX => {
                if self.out_intr_mbox.is_some() {
                    return ChannelOutcome::Host;
                }
                self.out_intr_mbox = Some(v);
            }
            _ => {}
        }
        ChannelOutcome::Done
    }
}
