//! The channels a host serves, typed: what a context waits on when the run comes back to
//! the host, and which signal-notification register a write goes to.

use spu_isa::machine::ch;

/// A channel an SPU can wait on that only the host (or another SPU's signal) makes ready.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Channel {
    /// `SPU_RdInMbox` (29): the inbound mailbox is empty; write it with
    /// [`System::write_in_mbox`](crate::System::write_in_mbox).
    InMbox,
    /// `SPU_WrOutMbox` (28): the outbound mailbox is full; read it with
    /// [`System::read_out_mbox`](crate::System::read_out_mbox).
    OutMbox,
    /// `SPU_WrOutIntrMbox` (30): the outbound interrupt mailbox is full; read it with
    /// [`System::read_out_intr_mbox`](crate::System::read_out_intr_mbox).
    OutIntrMbox,
    /// `SPU_RdSigNotify1` (3) or `SPU_RdSigNotify2` (4): no signal is pending.
    Signal(Signal),
    /// `SPU_RdEventStat` (0): no enabled event is pending.
    Events,
    /// Any other channel, by number.
    Other(u8),
}

impl Channel {
    /// The channel with hardware number `n`.
    pub fn from_number(n: u8) -> Channel {
        match n {
            ch::RD_IN_MBOX => Channel::InMbox,
            ch::WR_OUT_MBOX => Channel::OutMbox,
            ch::WR_OUT_INTR_MBOX => Channel::OutIntrMbox,
            ch::RD_SIG_NOTIFY1 => Channel::Signal(Signal::One),
            ch::RD_SIG_NOTIFY2 => Channel::Signal(Signal::Two),
            ch::RD_EVENT_STAT => Channel::Events,
            other => Channel::Other(other),
        }
    }

    /// The hardware channel number.
    pub fn number(self) -> u8 {
        match self {
            Channel::InMbox => ch::RD_IN_MBOX,
            Channel::OutMbox => ch::WR_OUT_MBOX,
            Channel::OutIntrMbox => ch::WR_OUT_INTR_MBOX,
            Channel::Signal(Signal::One) => ch::RD_SIG_NOTIFY1,
            Channel::Signal(Signal::Two) => ch::RD_SIG_NOTIFY2,
            Channel::Events => ch::RD_EVENT_STAT,
            Channel::Other(n) => n,
        }
    }
}

/// One of the two signal-notification registers (libspe2's `SPE_SIG_NOTIFY_REG_1`, `_2`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Signal {
    /// Signal-notification register 1.
    One,
    /// Signal-notification register 2.
    Two,
}

impl Signal {
    /// 0 for register 1, 1 for register 2.
    pub fn index(self) -> usize {
        match self {
            Signal::One => 0,
            Signal::Two => 1,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_round_trip() {
        for n in 0..=127u8 {
            assert_eq!(Channel::from_number(n).number(), n);
        }
        assert_eq!(Channel::from_number(29), Channel::InMbox);
        assert_eq!(Channel::from_number(4), Channel::Signal(Signal::Two));
    }
}
