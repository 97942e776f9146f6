//! The causes an instruction waits for, shared by the timing model that charges the stalls
//! and the profile that counts and reports them.

/// Why an instruction waited (the stall classes IBM's simulator reports).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum StallCause {
    /// Waiting for a source register that an earlier instruction has not produced yet.
    Dependency,
    /// Refilling the pipeline after a mispredicted (unhinted or wrongly hinted) taken branch.
    BranchMiss,
    /// Waiting for a branch hint to complete before its branch can issue.
    Hint,
    /// Held behind a double-precision instruction, which blocks issue for several cycles.
    DoublePrecision,
    /// Blocked on a channel read or write; the value is the channel number.
    Channel(u8),
    /// Waiting for the instruction fetch to bring in the next line from local store.
    Fetch,
}

impl StallCause {
    /// Index of the cause's counter in [`crate::profile::PcStats::stall`].
    pub const fn index(self) -> usize {
        match self {
            StallCause::Dependency => 0,
            StallCause::BranchMiss => 1,
            StallCause::Hint => 2,
            StallCause::DoublePrecision => 3,
            StallCause::Channel(_) => 4,
            StallCause::Fetch => 5,
        }
    }

    /// Short column names, in index order.
    pub const NAMES: [&'static str; 6] = ["dep", "branch", "hint", "dp", "chan", "fetch"];
}

/// Number of stall classes.
pub const STALL_CLASSES: usize = 6;
