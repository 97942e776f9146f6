//! An optional per-SPU log of the MFC commands an SPU issues and the channel waits it
//! makes, with their simulated cycles: what heat maps and timelines are drawn from. Off by
//! default; when off it costs one branch per DMA command and per channel stall, none on
//! the instruction paths.

use super::channels::ChannelOutcome;
use super::spu::Spu;

/// One entry of an SPU's event log.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum SpuEvent {
    /// An MFC command entered the queue at `cycle`; `complete` is when its transfer is done
    /// (the latest of its tag's queued commands; `cycle` for commands that queue nothing).
    Dma {
        /// The SPU cycle the command was queued.
        cycle: u64,
        /// The SPU cycle its tag group's transfers are done.
        complete: u64,
        /// The MFC command opcode (`get`, `put`, list and atomic variants).
        cmd: u8,
        /// The local-store byte address of the transfer.
        lsa: u32,
        /// The main-memory effective address of the transfer.
        ea: u64,
        /// The transfer size in bytes (for lists, the list's size in bytes).
        size: u32,
        /// The command's tag group (0 to 31).
        tag: u8,
    },
    /// A channel instruction could not proceed at `cycle` and waited until `until` (the
    /// data's arrival, or the quantum boundary).
    ChannelWait {
        /// The SPU cycle the channel instruction first tried.
        cycle: u64,
        /// The SPU cycle it could proceed (or the quantum ended).
        until: u64,
        /// The channel number.
        channel: u8,
    },
}

impl Spu {
    /// Starts logging [`SpuEvent`]s (cleared).
    pub fn enable_event_log(&mut self) {
        self.events = Some(Vec::new());
    }

    /// The events logged since the last call (empty when the log is off).
    pub fn take_events(&mut self) -> Vec<SpuEvent> {
        self.events.as_mut().map(std::mem::take).unwrap_or_default()
    }

    /// Logs the MFC command just issued with `cmd` at `now`, if it was accepted.
    pub(super) fn log_mfc_command(&mut self, cmd: u8, now: u64, outcome: &ChannelOutcome) {
        if !matches!(outcome, ChannelOutcome::Done) {
            return;
        }
        let tag = (self.core.mfc.tag_id & 31) as u8;
        let complete = self
            .queue
            .iter()
            .filter(|c| c.tag == tag)
            .map(|c| c.complete)
            .max()
            .unwrap_or(now)
            .max(now);
        let event = SpuEvent::Dma {
            cycle: now,
            complete,
            cmd,
            lsa: self.core.mfc.lsa,
            ea: ((self.core.mfc.eah as u64) << 32) | self.core.mfc.eal as u64,
            size: self.core.mfc.size,
            tag,
        };
        if let Some(log) = &mut self.events {
            log.push(event);
        }
    }

    pub(super) fn log_channel_wait(&mut self, cycle: u64, until: u64, channel: u8) {
        if let Some(log) = &mut self.events {
            log.push(SpuEvent::ChannelWait {
                cycle,
                until,
                channel,
            });
        }
    }
}
